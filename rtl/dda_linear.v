// dda_linear: exact DDA (Bresenham over path ticks) for one axis of a linear segment.
//
// A segment lasts T ticks (T = total) and this axis must emit n steps (n <= T). With the
// remainder r (0 <= r < T, cleared by load), each tick does
//     if (r + n >= T) { step; r = r + n - T } else { r = r + n }
// so after t ticks exactly floor(t * n / T) steps have been emitted: the k-th step falls on tick
// ceil(k * T / n), within one tick of its ideal time k * T / n, and the last one on tick T. The
// two candidate updates (r - (T - n) and r + n) are computed in parallel from registers, the
// compare is the borrow of the first one: one 64-bit add deep.
// The executor gives one tick per clock for constant-rate segments; a rate generator can gate
// `tick` to follow a speed profile, the arithmetic stays exact (the oversampled DDA of system.md).
// load: takes steps (n) and tmn = T - n (load wins over a tick on the same edge: the executor loads
// the next segment on the edge that ends the last tick of the current one; that tick's step is
// still issued, being combinational). step is combinational from the registers and tick.
// The end of a segment is counted by the executor (a tick counter), not derived from `step`, so no
// logic follows the 64-bit compare into a register enable.
`default_nettype none

module dda_linear (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [31:0] steps,
    input wire [63:0] tmn,
    input wire        tick,

    output wire step  // this tick emits a step
);

  reg [63:0] rem_reg;
  reg [31:0] n_reg;
  reg [63:0] tmn_reg;
  reg [31:0] left_reg;

  wire [64:0] diff = {1'b0, rem_reg} - {1'b0, tmn_reg};  // r + n - T
  wire        wrap = !diff[64];                           // r + n >= T
  wire        active = tick && (left_reg != 32'd0);

  always @(posedge clk) begin
    if (load) begin
      rem_reg  <= 64'd0;
      n_reg    <= steps;
      tmn_reg  <= tmn;
      left_reg <= steps;
    end else if (active) begin
      if (wrap) begin
        rem_reg  <= diff[63:0];
        left_reg <= left_reg - 32'd1;
      end else begin
        rem_reg <= rem_reg + {32'd0, n_reg};
      end
    end
    if (rst) begin
      rem_reg  <= 64'd0;
      n_reg    <= 32'd0;
      tmn_reg  <= 64'd0;
      left_reg <= 32'd0;
    end
  end

  assign step = active && wrap;

endmodule

`default_nettype wire
