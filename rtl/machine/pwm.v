// pwm: a PWM generator with a period of PWM_DIV * 2^PWM_BITS clocks (default 4883 * 1024 clocks:
// 10.0 Hz at 50 MHz, a heater MOSFET's rate; docs/heater.md), also the part-cooling fan's
// (docs/protocol.md "OUTPUT").
//
// Contract
//   duty        requested duty in counts, 0 .. 2^PWM_BITS (2^PWM_BITS and above: always on). It is
//               taken into the active duty only at a period boundary, so every period is whole.
//   force_off   output low from the clock after it rises (not waiting for the boundary); the
//               period counter keeps running.
//   out         registered: high for the first `active duty` counts of each period.
//   period_start 1-clock strobe on the clock the active duty is loaded (count 0 of a period).
//   active      the active duty (what out follows), for status.
// Latency: force_off at edge E -> out low after edge E + 1. duty -> out from the next boundary.
// No multiplier, no divider. rst is synchronous, active high (out low, counters 0, duty 0).
`default_nettype none

module pwm #(
    parameter PWM_BITS = 10,
    parameter PWM_DIV  = 4883
) (
    input wire clk,
    input wire rst,

    input wire [PWM_BITS:0] duty,
    input wire              force_off,

    output wire              out,
    output wire              period_start,
    output wire [PWM_BITS:0] active
);

  localparam DW = (PWM_DIV > 1) ? $clog2(PWM_DIV) : 1;
  localparam integer DIV_LAST_I = PWM_DIV - 1;
  localparam [DW-1:0] DIV_LAST = DIV_LAST_I[DW-1:0];

  reg [      DW-1:0] div_reg;
  reg [PWM_BITS-1:0] cnt_reg;
  reg [  PWM_BITS:0] active_reg;
  reg                out_reg;
  reg                start_reg;

  wire               div_wrap = (div_reg == DIV_LAST);
  wire               boundary = div_wrap && (cnt_reg == {PWM_BITS{1'b1}});
  // Count that the output shows in the next clock, and its duty.
  wire [PWM_BITS-1:0] cnt_next = div_wrap ? cnt_reg + 1'b1 : cnt_reg;
  wire [  PWM_BITS:0] duty_next = boundary ? duty : active_reg;

  always @(posedge clk) begin
    div_reg   <= div_wrap ? {DW{1'b0}} : div_reg + 1'b1;
    if (div_wrap) cnt_reg <= cnt_next;
    if (boundary) active_reg <= duty;
    start_reg <= boundary;
    out_reg   <= !force_off && ({1'b0, cnt_next} < duty_next);
    if (rst) begin
      div_reg    <= {DW{1'b0}};
      cnt_reg    <= {PWM_BITS{1'b0}};
      active_reg <= {(PWM_BITS + 1) {1'b0}};
      start_reg  <= 1'b0;
      out_reg    <= 1'b0;
    end
  end

  assign out          = out_reg;
  assign period_start = start_reg;
  assign active       = active_reg;

endmodule

`default_nettype wire
