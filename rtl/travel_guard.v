// travel_guard: the device's soft limits (docs/machine.md "Soft limits"): per axis a travel
// [min, max] in steps and an enable, the queued end position (where the last accepted motion
// entry ends), and the check of a motion frame's end against the travel.
//
// Contract
//   cfg_wr         1-clock strobe: axis cfg_axis gets enable cfg_en and travel [cfg_min, cfg_max]
//                  (signed steps) from the next edge. cfg_axis >= N_AXES writes nothing. Every
//                  axis is disabled after rst.
//   load, delta    load: 1-clock strobe on the edge that takes a frame's last byte; delta (signed
//                  32-bit steps per axis, axis a in [32*a+:32]; 0 for an axis the frame does not
//                  move, and for a frame that moves nothing) is registered then.
//   ok             for the delta last loaded: every enabled axis's end (queued + delta, 33-bit
//                  signed) lies in [min, max] (two signed 33-bit compares per axis). From
//                  registers only; read it in the CHECK clock (the clock after load).
//   accept         1-clock strobe: the loaded frame was accepted into the FIFO (the decoder
//                  accepts a motion frame only with ok): queued += delta on the next edge.
//   resync, pos    the queue was flushed (e-stop, hard limit, abort): queued <= pos (the position
//                  counters, axis a in [32*a+:32]) on the next edge; wins over accept.
// The queued end position per axis is 0 after rst, as the position counters are.
// A disabled axis is never refused; its queued end still follows the entries (wrapping at 32
// bits as the position counters do), so enabling it later checks from where the queue ends.
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

    input wire                   load,
    input wire [32*N_AXES-1:0]   delta,
    input wire                   accept,
    input wire                   resync,
    input wire [32*N_AXES-1:0]   pos,

    output wire                  ok
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      travel_guard_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  reg [  N_AXES-1:0] en_reg;
  reg [32*N_AXES-1:0] min_reg, max_reg, delta_reg, queued_reg;
  reg [  N_AXES-1:0] in_ok;

  // The ends of the loaded frame and their compares (33-bit signed: no overflow at +-2^31).
  integer i;
  always @(*) begin : ends
    reg signed [32:0] e, lo, hi;
    for (i = 0; i < N_AXES; i = i + 1) begin
      e = {queued_reg[32*i+31], queued_reg[32*i+:32]} + {delta_reg[32*i+31], delta_reg[32*i+:32]};
      lo = {min_reg[32*i+31], min_reg[32*i+:32]};
      hi = {max_reg[32*i+31], max_reg[32*i+:32]};
      in_ok[i] = !en_reg[i] || (e >= lo && e <= hi);
    end
  end

  always @(posedge clk) begin : regs
    integer a;
    if (cfg_wr) begin
      for (a = 0; a < N_AXES; a = a + 1)
        if (cfg_axis == a[3:0]) begin
          en_reg[a]        <= cfg_en;
          min_reg[32*a+:32] <= cfg_min;
          max_reg[32*a+:32] <= cfg_max;
        end
    end
    if (load) delta_reg <= delta;
    if (resync) begin
      queued_reg <= pos;
    end else if (accept) begin
      for (a = 0; a < N_AXES; a = a + 1)
        queued_reg[32*a+:32] <= queued_reg[32*a+:32] + delta_reg[32*a+:32];
    end
    if (rst) begin
      en_reg     <= {N_AXES{1'b0}};
      min_reg    <= {32 * N_AXES{1'b0}};
      max_reg    <= {32 * N_AXES{1'b0}};
      delta_reg  <= {32 * N_AXES{1'b0}};
      queued_reg <= {32 * N_AXES{1'b0}};
    end
  end

  assign ok = &in_ok;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set travel_guard, k-induction; covers). Reset in the
  // first clock; every input free except that the decoder accepts only what the guard passed
  // (accept implies ok: frame_decoder answers NAK TRAVEL otherwise).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(*) if (accept) assume (ok);

  // An independent end of axis 0 (64-bit signed arithmetic).
  wire signed [63:0] f_end0 = $signed(queued_reg[31:0]) + $signed(delta_reg[31:0]);
  wire signed [63:0] f_q0 = $signed(queued_reg[31:0]);

  always @(*)
    if (f_past_valid && !rst) begin
      // Axis 0's verdict is the 64-bit compare.
      if (en_reg[0] && (f_end0 > $signed(max_reg[31:0]) || f_end0 < $signed(min_reg[31:0])))
        assert (!ok);
      if (!en_reg) assert (ok);
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst) begin
      // A frame accepted on an enabled axis leaves the queued end inside the travel (the
      // travel as it was when the frame was checked).
      if ($past(accept && !resync && en_reg[0]))
        assert (f_q0 >= $signed($past(min_reg[31:0])) && f_q0 <= $signed($past(max_reg[31:0])));
      // The queued end moves by exactly the accepted delta, follows pos on a resync, and
      // otherwise stays.
      if ($past(resync)) assert (queued_reg == $past(pos));
      else if ($past(accept))
        assert (queued_reg[31:0] == $past(queued_reg[31:0]) + $past(delta_reg[31:0]));
      else assert (queued_reg == $past(queued_reg));
      // The enable changes only by a configuration write.
      if (en_reg != $past(en_reg)) assert ($past(cfg_wr));
      // Covers: a frame refused beyond max and below min; a frame accepted ending exactly on
      // max; a resync.
      cover (en_reg[0] && !ok && f_end0 > $signed(max_reg[31:0]));
      cover (en_reg[0] && !ok && f_end0 < $signed(min_reg[31:0]));
      cover ($past(accept && en_reg[0]) && f_q0 == $signed(max_reg[31:0]) && max_reg[31:0] != 0);
      cover ($past(resync) && queued_reg != $past(queued_reg));
    end
`endif

endmodule

`default_nettype wire
