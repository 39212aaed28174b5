// estop_latch: cnc_core's e-stop input (docs/architecture.md "E-stop", docs/protocol.md "E-stop").
//
// Contract
//   estop        active high, asynchronous: two-flop synchronizer; active is its output (the pin's
//                level two edges later).
//   latched      set by an edge on which active is high, cleared by one on which fault_clear is
//                high and active low; STATUS faults bit 4.
//   stop         active or latched: cnc_core holds the FIFO flushed, aborts segment_prep and
//                segment_executor and keeps the laser, the machine outputs and the heaters low.
//   rst          synchronous: all 0.
`default_nettype none

module estop_latch (
    input wire clk,
    input wire rst,

    input  wire estop,
    input  wire fault_clear,
    output wire active,
    output wire latched,
    output wire stop
);

  reg estop_s1_reg, estop_s2_reg, estop_latch_reg;
  always @(posedge clk) begin
    estop_s1_reg <= estop;
    estop_s2_reg <= estop_s1_reg;
    if (fault_clear && !estop_s2_reg) estop_latch_reg <= 1'b0;
    if (estop_s2_reg) estop_latch_reg <= 1'b1;
    if (rst) begin
      estop_s1_reg    <= 1'b0;
      estop_s2_reg    <= 1'b0;
      estop_latch_reg <= 1'b0;
    end
  end
  assign active  = estop_s2_reg;
  assign latched = estop_latch_reg;
  assign stop    = estop_s2_reg || estop_latch_reg;

endmodule

`default_nettype wire
