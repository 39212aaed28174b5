// uart_rx: 8N1 UART receiver (LSB first, line idle high) with an AXI-Stream byte output
// (docs/protocol.md "Physical").
//
// Contract
//   rxd            asynchronous pin; passes a two-flop synchronizer before any use.
//   m_axis_*       1-byte output register. m_axis_tvalid rises with a received byte and stays
//                  high (tdata stable) until a clock edge with m_axis_tready high accepts it.
//   busy           high from start-bit detection until the stop bit has been sampled.
//   frame_error    1-clock strobe: the stop bit was sampled low. The byte is dropped, and the
//                  receiver waits for the line to return high before it looks for a new start
//                  bit (a held-low line or break gives one strobe, not one per 10 bits).
//   overrun_error  1-clock strobe: a good byte completed while the previous byte was still
//                  unaccepted (m_axis_tvalid high and m_axis_tready low on that clock). The new
//                  byte is dropped; the byte held in the output register is kept.
//   After reset the line must be seen high once before the first start bit is accepted.
//
// Bit timer
//   A fractional (phase-accumulator) timer: acc += BAUD each clock and a bit tick fires when acc
//   reaches CLK_HZ (then acc -= CLK_HZ), so the average bit period is exactly CLK_HZ / BAUD
//   clocks even when that is not an integer. Both constants are divided by gcd(CLK_HZ, BAUD)
//   first (same tick sequence, narrower accumulator). On start detection the accumulator is
//   preloaded with (MOD + INC) / 2, so the first tick falls at the middle of the start bit and
//   every later tick at a bit centre (each within 1 clock of its ideal time, no accumulated
//   drift). No divider exists in the hardware: every / and % here is a constant expression.
//
// Timing (P = CLK_HZ / BAUD clocks per bit)
//   pin falling edge -> start detected: 2-3 clocks (synchronizer).
//   start detected -> start bit checked: about P/2 clocks; a low pulse shorter than about half a
//   bit is found high there and starts no byte (no tvalid, no frame_error).
//   start detected -> m_axis_tvalid / frame_error / overrun_error: about 9.5 * P + 1 clocks
//   (the stop bit is sampled at its centre; the receiver is idle again from that clock on, so it
//   tolerates a sender up to several percent fast or slow; +-2% is tested).
//   Requires CLK_HZ >= 8 * BAUD (3 Mbaud at 50 MHz gives P = 16.7).
`default_nettype none

module uart_rx #(
    parameter CLK_HZ = 50_000_000,
    parameter BAUD   = 115_200
) (
    input  wire       clk,
    input  wire       rst,            // synchronous, active high
    input  wire       rxd,            // asynchronous pin, idle high
    output wire [7:0] m_axis_tdata,
    output wire       m_axis_tvalid,
    input  wire       m_axis_tready,
    output wire       busy,
    output wire       frame_error,
    output wire       overrun_error
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
  localparam [31:0] WRAP_32 = MOD - INC;  // acc >= this: acc + INC >= MOD, a bit tick
  localparam [ACC_W-1:0] ACC_INC = INC_32[ACC_W-1:0];
  localparam [ACC_W-1:0] ACC_WRAP = WRAP_32[ACC_W-1:0];
  localparam [31:0] HALF_32 = (MOD + INC) / 2;  // preload: first tick at mid start bit
  localparam [ACC_W-1:0] ACC_HALF = HALF_32[ACC_W-1:0];

  localparam [1:0] STATE_WAIT_HIGH = 2'd0;  // after reset or a frame error: wait for idle line
  localparam [1:0] STATE_IDLE = 2'd1;  // line high: a low level is a start bit
  localparam [1:0] STATE_FRAME = 2'd2;  // receiving: start, 8 data and stop bits

  localparam [3:0] BIT_START = 4'd0;
  localparam [3:0] BIT_STOP = 4'd9;

  reg rxd_meta_reg, rxd_sync_reg;
  reg [1:0] state_reg;
  reg [3:0] bit_cnt_reg;  // bit being received: 0 start, 1..8 data, 9 stop
  reg [ACC_W-1:0] acc_reg;
  reg [7:0] shift_reg;
  reg [7:0] m_axis_tdata_reg;
  reg m_axis_tvalid_reg;
  reg frame_error_reg, overrun_error_reg;

  assign m_axis_tdata = m_axis_tdata_reg;
  assign m_axis_tvalid = m_axis_tvalid_reg;
  assign busy = (state_reg == STATE_FRAME);
  assign frame_error = frame_error_reg;
  assign overrun_error = overrun_error_reg;

  wire bit_tick = (acc_reg >= ACC_WRAP);

  // Two-flop synchronizer for the asynchronous pin; resets to the idle level.
  always @(posedge clk) begin
    if (rst) begin
      rxd_meta_reg <= 1'b1;
      rxd_sync_reg <= 1'b1;
    end else begin
      rxd_meta_reg <= rxd;
      rxd_sync_reg <= rxd_meta_reg;
    end
  end

  always @(posedge clk) begin
    // defaults
    frame_error_reg <= 1'b0;
    overrun_error_reg <= 1'b0;
    if (m_axis_tready) m_axis_tvalid_reg <= 1'b0;

    case (state_reg)
      STATE_WAIT_HIGH: begin
        if (rxd_sync_reg) state_reg <= STATE_IDLE;
      end
      STATE_IDLE: begin
        if (!rxd_sync_reg) begin
          state_reg <= STATE_FRAME;
          bit_cnt_reg <= BIT_START;
          acc_reg <= ACC_HALF;
        end
      end
      default: begin  // STATE_FRAME
        if (bit_tick) begin
          acc_reg <= acc_reg - ACC_WRAP;
          bit_cnt_reg <= bit_cnt_reg + 4'd1;
          if (bit_cnt_reg == BIT_START) begin
            // Start bit confirmed only if still low at its centre; else it was a glitch.
            if (rxd_sync_reg) state_reg <= STATE_IDLE;
          end else if (bit_cnt_reg == BIT_STOP) begin
            if (!rxd_sync_reg) begin
              frame_error_reg <= 1'b1;
              state_reg <= STATE_WAIT_HIGH;
            end else begin
              state_reg <= STATE_IDLE;
              if (m_axis_tvalid_reg && !m_axis_tready) begin
                overrun_error_reg <= 1'b1;
              end else begin
                m_axis_tdata_reg <= shift_reg;
                m_axis_tvalid_reg <= 1'b1;
              end
            end
          end else begin
            shift_reg <= {rxd_sync_reg, shift_reg[7:1]};  // LSB first
          end
        end else begin
          acc_reg <= acc_reg + ACC_INC;
        end
      end
    endcase

    if (rst) begin
      state_reg <= STATE_WAIT_HIGH;
      bit_cnt_reg <= BIT_START;
      acc_reg <= {ACC_W{1'b0}};
      shift_reg <= 8'd0;
      m_axis_tdata_reg <= 8'd0;
      m_axis_tvalid_reg <= 1'b0;
      frame_error_reg <= 1'b0;
      overrun_error_reg <= 1'b0;
    end
  end

endmodule

`default_nettype wire
