// dda_linear: exact DDA (Bresenham over path ticks) for one axis of a linear segment.
//
// A segment lasts T ticks (T = total) and this axis must emit n steps (n <= T). With the
// remainder r (0 <= r < T, cleared by load), each tick does
//     if (r + n >= T) { step; r = r + n - T } else { r = r + n }
// so after t ticks exactly floor(t * n / T) steps have been emitted: the k-th step falls on tick
// ceil(k * T / n), within one tick of its ideal time k * T / n, and the last one on tick T.
// Implementation (same ticks, same steps): the register holds s = r - (T - n) = r + n - T, a
// 65-bit two's-complement value in [n - T, n), instead of r. The step condition r + n >= T is
// then s >= 0, the sign bit of a register (no carry chain between the registers and `step`, so
// nothing follows a 64-bit compare into step_pulse or the position counters), and the update is
//     s >= 0 (step):  r' = s      ->  s' = s - (T - n)
//     s <  0:         r' = r + n  ->  s' = s + n        (= r + n - T + n)
// two 65-bit candidates computed in parallel from registers, selected by the sign bit: one
// 65-bit add deep, ending at the register. load sets s = -(T - n) (r = 0).
// The executor gives one tick per clock for constant-rate segments; a rate generator can gate
// `tick` to follow a speed profile, the arithmetic stays exact (the oversampled DDA, docs/motion.md).
// load: takes steps (n) and tmn = T - n (load wins over a tick on the same edge: the executor loads
// the next segment on the edge that ends the last tick of the current one; that tick's step is
// still issued, being combinational). step is combinational from the registers and tick.
// The end of a segment is counted by the executor (a tick counter), not derived from `step`, so no
// logic follows the 64-bit compare into a register enable.
// TMN_FROM_TOTAL = 1 (cnc_core's protocol-v1 build, whose segment_prep holds no T - n): load takes
// T from `total` instead of `tmn` and computes T - n (tmn_reg) and n - T (s) itself, two 65-bit
// subtracts in parallel from the inputs; the registers get the same values as with tmn = T - n.
// STEP_GUARD = 0: no steps-left counter (left_reg). It only guards against more than n steps,
// which cannot happen within the T ticks a load is given (floor(t * n / T) <= n for t <= T); the
// caller must tick at most T times per load (segment_executor's tick counter does).
`default_nettype none

module dda_linear #(
    parameter TMN_FROM_TOTAL = 0,  // 1: T from `total` (tmn unused), 0: T - n from `tmn` (total unused)
    parameter STEP_GUARD     = 1   // 0: no steps-left counter (at most T ticks per load)
) (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [31:0] steps,
    /* verilator lint_off UNUSEDSIGNAL */
    input wire [63:0] tmn,    // T - n (TMN_FROM_TOTAL = 0)
    input wire [63:0] total,  // T (TMN_FROM_TOTAL = 1)
    /* verilator lint_on UNUSEDSIGNAL */
    input wire        tick,

    output wire step  // this tick emits a step
);

  reg [64:0] s_reg;  // r + n - T (two's complement; see above)
  reg [31:0] n_reg;
  reg [63:0] tmn_reg;
  reg [31:0] left_reg;

  wire        wrap = !s_reg[64];  // r + n >= T
  wire        active = tick && (STEP_GUARD == 0 || left_reg != 32'd0);

  // The 65-bit sums are written in the branches whose registers they feed: the same logic as
  // continuous assignments, and a simulator evaluates them only on the clocks that branch runs
  // (docs/architecture.md "Simulation speed").
  always @(posedge clk) begin
    if (load) begin
      s_reg    <= (TMN_FROM_TOTAL != 0) ? {33'd0, steps} - {1'b0, total}  // n - T: r = 0
                                        : 65'd0 - {1'b0, tmn};           // -(T - n)
      n_reg    <= steps;
      tmn_reg  <= (TMN_FROM_TOTAL != 0) ? total - {32'd0, steps} : tmn;
      left_reg <= steps;
    end else if (active) begin
      if (wrap) begin
        s_reg    <= s_reg - {1'b0, tmn_reg};  // s - (T - n)
        left_reg <= left_reg - 32'd1;
      end else begin
        s_reg <= s_reg + {33'd0, n_reg};  // s + n
      end
    end
    if (rst) begin
      s_reg    <= 65'd0;
      n_reg    <= 32'd0;
      tmn_reg  <= 64'd0;
      left_reg <= 32'd0;
    end
  end

  assign step = active && wrap;

endmodule

`default_nettype wire
