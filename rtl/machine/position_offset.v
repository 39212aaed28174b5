// position_offset: the machine position of each axis as SET_POSITION defines it (docs/machine.md
// "Homing and probing (hardware)"): the executor's step counters (STEP rising edges since rst,
// signed) plus a per-axis offset that a SET_POSITION sets, so that the counters themselves (and
// segment_executor) are untouched.
//
// Contract
//   raw        the executor's position counters (axis a in [32*a+:32]), registers.
//   wr[a]      1-clock strobe: axis a's position becomes wdata[32*a+:32]: off[a] takes
//              wdata - raw (mod 2^32) on the edge after it, so from the next clock position[a] =
//              wdata while raw does not change (SET_POSITION is accepted only while the motion is
//              idle; a step in the wr clock itself would be counted on top of wdata).
//   position   raw + off per axis (mod 2^32): one 32-bit add after the counter register, no
//              register of its own, so it follows a STEP rise on the same edge as raw.
//   rst        synchronous: every offset 0 (position = raw).
// Resources: 32 offset flops, a 32-bit subtract (written on wr only) and a 32-bit add per axis.
`default_nettype none

module position_offset #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire [32*N_AXES-1:0] raw,
    input wire [  N_AXES-1:0] wr,
    input wire [32*N_AXES-1:0] wdata,

    output wire [32*N_AXES-1:0] position
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      position_offset_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  reg [32*N_AXES-1:0] off_reg;

  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_axis
      always @(posedge clk) begin
        if (wr[a]) off_reg[32*a+:32] <= wdata[32*a+:32] - raw[32*a+:32];
        if (rst) off_reg[32*a+:32] <= 32'd0;
      end
      assign position[32*a+:32] = raw[32*a+:32] + off_reg[32*a+:32];
    end
  endgenerate

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set position_offset: induction, Yosys SAT). Reset in the
  // first clock; every input free.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  integer k;
  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst)
      for (k = 0; k < N_AXES; k = k + 1) begin
        // After a write the position is the value written, as long as the counter has not moved.
        if ($past(wr[k]) && raw[32*k+:32] == $past(raw[32*k+:32]))
          assert (position[32*k+:32] == $past(wdata[32*k+:32]));
        // Without a write the position follows the counter exactly (the offset stays).
        if (!$past(wr[k]))
          assert (position[32*k+:32] - raw[32*k+:32] ==
                  $past(position[32*k+:32]) - $past(raw[32*k+:32]));
      end
  always @(posedge clk)
    if (f_past_valid && $past(rst)) assert (position == raw);
`endif

endmodule

`default_nettype wire
