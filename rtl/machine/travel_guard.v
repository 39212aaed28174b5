// travel_guard: the device's soft limits (docs/machine.md "Soft limits"): per axis a travel
// [min, max] in steps and an enable, the queued end position (where the last accepted motion
// entry ends), and the check of a motion frame's end against the travel.
//
// Contract
//   cfg_wr         1-clock strobe: axis cfg_axis gets enable cfg_en and travel [cfg_min, cfg_max]
//                  (signed steps) from the next edge. cfg_axis >= N_AXES writes nothing. Every
//                  axis is disabled after rst.
//   delta          signed 32-bit steps per axis of the frame being checked (axis a in [32*a+:32];
//                  0 for an axis the frame does not move), held by the caller from the check
//                  edge until its accept.
//   check          1-clock strobe (frame_decoder: the edge that takes a frame's last byte): ok is
//                  registered from every enabled axis's end, queued + delta (33-bit signed), lying
//                  in [min, max] (two signed 33-bit compares per axis), with the registers as they
//                  are before that edge.
//   ok             register: the verdict of the last check (1 after rst); read it in the clock
//                  after check (the decoder's CHECK clock).
//   accept         1-clock strobe: the checked frame was accepted into the FIFO (the decoder
//                  accepts a motion frame only with ok): queued += delta on the next edge.
//   resync, pos    the queue is flushed (e-stop, hard limit): queued <= pos (the position
//                  counters, axis a in [32*a+:32]) on the next edge; wins over accept.
// A disabled axis is never refused; its queued end still follows the entries (wrapping at 32
// bits as the position counters do), so enabling it later checks from where the queue ends. The
// queued end is 0 after rst, as the position counters are. All arithmetic is formed inside the
// branch of the strobe that uses it (check, accept), so idle clocks compute nothing.
// Requires 1 <= N_AXES <= 15. rst is synchronous, active high.
`default_nettype none

module travel_guard #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire        cfg_wr,
    input wire [ 3:0] cfg_axis,
    input wire        cfg_en,
    input wire [31:0] cfg_min,
    input wire [31:0] cfg_max,

    input wire                 check,
    input wire [32*N_AXES-1:0] delta,
    input wire                 accept,
    input wire                 resync,
    input wire [32*N_AXES-1:0] pos,

    output wire ok
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      travel_guard_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  reg [N_AXES-1:0] en_reg;
  reg [32*N_AXES-1:0] min_reg, max_reg, queued_reg;
  reg ok_reg;

  always @(posedge clk) begin : regs
    integer a;
    reg signed [32:0] e, lo, hi;
    reg all_in;
    if (cfg_wr) begin
      for (a = 0; a < N_AXES; a = a + 1)
        if (cfg_axis == a[3:0]) begin
          en_reg[a]         <= cfg_en;
          min_reg[32*a+:32] <= cfg_min;
          max_reg[32*a+:32] <= cfg_max;
        end
    end
    if (check) begin
      all_in = 1'b1;
      for (a = 0; a < N_AXES; a = a + 1) begin
        e  = {queued_reg[32*a+31], queued_reg[32*a+:32]} + {delta[32*a+31], delta[32*a+:32]};
        lo = {min_reg[32*a+31], min_reg[32*a+:32]};
        hi = {max_reg[32*a+31], max_reg[32*a+:32]};
        if (en_reg[a] && (e < lo || e > hi)) all_in = 1'b0;
      end
      ok_reg <= all_in;
    end
    if (resync) begin
      queued_reg <= pos;
    end else if (accept) begin
      for (a = 0; a < N_AXES; a = a + 1)
        queued_reg[32*a+:32] <= queued_reg[32*a+:32] + delta[32*a+:32];
    end
    if (rst) begin
      en_reg     <= {N_AXES{1'b0}};
      min_reg    <= {32 * N_AXES{1'b0}};
      max_reg    <= {32 * N_AXES{1'b0}};
      queued_reg <= {32 * N_AXES{1'b0}};
      ok_reg     <= 1'b1;
    end
  end

  assign ok = ok_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set travel_guard, k-induction; covers). Reset in the
  // first clock; inputs free except as the decoder drives them: accept only in the clock after a
  // check, with ok, the same delta, and no configuration write or resync on that check edge.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(posedge clk)
    if (f_past_valid && accept) begin
      assume ($past(check) && ok && delta == $past(delta));
      assume (!$past(cfg_wr) && !$past(resync) && !$past(rst) && !$past(accept));
    end
  always @(*) if (!f_past_valid) assume (!accept);

  // Axis 0 end with 64-bit signed arithmetic, for the check made on the previous edge.
  reg signed [63:0] f_end0, f_min0, f_max0;
  reg f_en0, f_en_any, f_check;
  always @(posedge clk) begin
    f_end0   <= $signed(queued_reg[31:0]) + $signed(delta[31:0]);
    f_min0   <= $signed(min_reg[31:0]);
    f_max0   <= $signed(max_reg[31:0]);
    f_en0    <= en_reg[0];
    f_en_any <= |en_reg;
    f_check  <= check && !rst;
  end
  wire signed [63:0] f_q0 = $signed(queued_reg[31:0]);

  always @(*)
    if (f_past_valid && !rst && f_check) begin
      // Axis 0's verdict is the 64-bit compare; with every axis off everything passes.
      if (f_en0 && (f_end0 > f_max0 || f_end0 < f_min0)) assert (!ok);
      if (!f_en_any) assert (ok);
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst) begin
      // A frame accepted on an enabled axis leaves the queued end inside the travel.
      if ($past(accept && !resync && !cfg_wr) && en_reg[0] && $past(en_reg[0]))
        assert (f_q0 >= $signed(min_reg[31:0]) && f_q0 <= $signed(max_reg[31:0]));
      // The queued end moves by exactly the accepted delta, follows pos on a resync, and
      // otherwise stays.
      if ($past(resync)) assert (queued_reg == $past(pos));
      else if ($past(accept))
        assert (queued_reg[31:0] == $past(queued_reg[31:0]) + $past(delta[31:0]));
      else assert (queued_reg == $past(queued_reg));
      // The enable changes only by a configuration write; ok only by a check.
      if (en_reg != $past(en_reg)) assert ($past(cfg_wr));
      if (ok != $past(ok)) assert ($past(check));
      // Covers: a frame refused beyond max and below min; a frame accepted ending exactly on
      // max; a resync.
      cover (f_check && f_en0 && !ok && f_end0 > f_max0);
      cover (f_check && f_en0 && !ok && f_end0 < f_min0);
      cover ($past(accept) && en_reg[0] && f_q0 == $signed(max_reg[31:0]) && max_reg[31:0] != 0);
      cover ($past(resync) && queued_reg != $past(queued_reg));
    end
`endif

endmodule

`default_nettype wire
