// uart_tx: 8N1 UART transmitter (LSB first, line idle high) with an AXI-Stream byte input
// (docs/protocol.md "Physical").
//
// Contract
//   s_axis_*   a byte is taken on a clock edge with s_axis_tvalid and s_axis_tready high.
//              s_axis_tready is high while idle, and also during the last clock of a stop bit,
//              so a stream kept valid goes out back to back with no idle time between frames.
//              s_axis_tready depends on registers only (never on s_axis_tvalid).
//   txd        registered output, high when idle.
//   busy       high while a frame (start, 8 data, stop bit) is on the line.
//
// Bit timer
//   A fractional (phase-accumulator) timer: acc += BAUD each clock and a bit boundary falls when
//   acc reaches CLK_HZ (then acc -= CLK_HZ), so the average bit period is exactly CLK_HZ / BAUD
//   clocks even when that is not an integer. Both constants are divided by gcd(CLK_HZ, BAUD)
//   first (same boundaries, narrower accumulator). The accumulator is cleared when a byte is
//   accepted from idle and keeps its fraction across back-to-back frames, so boundary m of a
//   stream lies at ceil(m * CLK_HZ / BAUD) clocks after the first start edge: every boundary
//   within 1 clock of ideal, no accumulated drift. No divider exists in the hardware: every
//   / and % here is a constant expression.
//
// Timing (P = CLK_HZ / BAUD clocks per bit)
//   accept -> start bit: txd falls on the same clock edge that accepts the byte (the start bit
//   is on the pin in the first clock after the transfer: latency 1 clock, registered output).
//   frame length: 10 bits; bit k of a frame from idle begins ceil(k * P) clocks after the start
//   edge. s_axis_tready returns 10 bits after the start edge (during the last stop-bit clock).
`default_nettype none

module uart_tx #(
    parameter CLK_HZ = 50_000_000,
    parameter BAUD   = 115_200
) (
    input  wire       clk,
    input  wire       rst,            // synchronous, active high
    input  wire [7:0] s_axis_tdata,
    input  wire       s_axis_tvalid,
    output wire       s_axis_tready,
    output wire       txd,
    output wire       busy
);

  // Greatest common divisor, evaluated at elaboration only (constant function). 64 Euclid
  // steps are more than any pair of 32-bit values needs.
  function integer gcd;
    input integer a;
    input integer b;
    integer x, y, t, i;
    begin
      x = a;
      y = b;
      for (i = 0; i < 64; i = i + 1) begin
        if (y != 0) begin
          t = x % y;
          x = y;
          y = t;
        end
      end
      gcd = x;
    end
  endfunction

  localparam integer GCD = gcd(CLK_HZ, BAUD);
  localparam integer MOD = CLK_HZ / GCD;  // accumulator modulus: one bit = MOD / INC clocks
  localparam integer INC = BAUD / GCD;  // accumulator increment per clock
  localparam integer ACC_W = (MOD > 1) ? $clog2(MOD) : 1;  // holds 0 .. MOD - 1
  // Sized copies for the datapath: 32-bit constants, then the low ACC_W bits (all fit).
  localparam [31:0] INC_32 = INC;
  localparam [31:0] WRAP_32 = MOD - INC;  // acc >= this: acc + INC >= MOD, a boundary
  localparam [ACC_W-1:0] ACC_INC = INC_32[ACC_W-1:0];
  localparam [ACC_W-1:0] ACC_WRAP = WRAP_32[ACC_W-1:0];

  localparam [3:0] BIT_STOP = 4'd9;

  reg busy_reg;
  reg txd_reg;
  reg [3:0] bit_cnt_reg;  // bit on the line: 0 start, 1..8 data, 9 stop
  reg [8:0] shift_reg;  // bits still to send, LSB next; fills with 1s (stop, then idle)
  reg [ACC_W-1:0] acc_reg;

  wire bit_tick = (acc_reg >= ACC_WRAP);
  wire last_clock = busy_reg && bit_tick && (bit_cnt_reg == BIT_STOP);

  assign s_axis_tready = !busy_reg || last_clock;
  assign txd = txd_reg;
  assign busy = busy_reg;

  always @(posedge clk) begin
    if (busy_reg) begin
      if (bit_tick) begin
        acc_reg <= acc_reg - ACC_WRAP;
        txd_reg <= shift_reg[0];
        shift_reg <= {1'b1, shift_reg[8:1]};
        bit_cnt_reg <= bit_cnt_reg + 4'd1;
        if (bit_cnt_reg == BIT_STOP) begin
          busy_reg <= 1'b0;
          txd_reg <= 1'b1;
        end
      end else begin
        acc_reg <= acc_reg + ACC_INC;
      end
    end

    if (s_axis_tvalid && s_axis_tready) begin
      // Start bit now; the accumulator starts from zero unless this frame follows the previous
      // one back to back, where it keeps the fraction (assigned above).
      busy_reg <= 1'b1;
      txd_reg <= 1'b0;
      shift_reg <= {1'b1, s_axis_tdata};
      bit_cnt_reg <= 4'd0;
      if (!busy_reg) acc_reg <= {ACC_W{1'b0}};
    end

    if (rst) begin
      busy_reg <= 1'b0;
      txd_reg <= 1'b1;
      bit_cnt_reg <= 4'd0;
      shift_reg <= 9'h1ff;
      acc_reg <= {ACC_W{1'b0}};
    end
  end

endmodule

`default_nettype wire
