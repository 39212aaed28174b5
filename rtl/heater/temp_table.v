// temp_table: the host-loaded thermistor tables of the heater channels (65 breakpoints per
// channel, two channels) and the linear interpolation from a 12-bit ADC code to a
// temperature (docs/heater.md "Temperature").
//
// Contract
//   wr, wr_ch, wr_idx (0..64), wr_data (Q11.4): one entry written per clock.
//   start, ch, code: look code up in channel ch's table (sampled on the start edge; ignored while
//   busy). Entry i is the temperature at code 64*i; with i = code >> 6, f = code & 63:
//     temp = t[i] + ((t[i+1] - t[i]) * f >>> 6)     (arithmetic shift: floor), Q11.4.
//   temp, done: temp is registered and valid from the done strobe on.
//   Until a channel's last entry (index 64) has been written after reset, its lookups return
//   -2048 degC (0x8000): an enabled heater with no table trips MINTEMP.
// Memory: 128 words per channel (65 used), one write port and one registered read port, no
//   initial contents and no reset (block RAM, M10K); rst clears only the loaded flags.
// Latency: start at edge S -> done (and temp) high after edge S + 5. One 17 x 7-bit multiply (a small DSP
// block or LUTs), registered on both sides.
// rst is synchronous, active high (idle).
`default_nettype none

module temp_table (
    input wire clk,
    input wire rst,

    input wire        wr,
    input wire [ 0:0] wr_ch,
    input wire [ 6:0] wr_idx,
    input wire [15:0] wr_data,

    input  wire               start,
    input  wire [        0:0] ch,
    input  wire [       11:0] code,
    output wire signed [15:0] temp,
    output wire               done,
    output wire               busy
);

  localparam integer WORDS = 256;  // 2 channels x 128

  reg [15:0] mem[0:WORDS-1];
  reg [15:0] rdata_reg;
  reg [7:0] rd_addr_reg;

  reg [1:0] loaded_reg;  // entry 64 of the channel written since reset
  reg ch_reg;

  always @(posedge clk) begin
    if (wr) mem[{wr_ch, wr_idx}] <= wr_data;
  end
  always @(posedge clk) begin
    if (wr && wr_idx == 7'd64) loaded_reg[wr_ch] <= 1'b1;
    if (rst) loaded_reg <= 2'b00;
  end
  always @(posedge clk) begin
    rdata_reg <= mem[rd_addr_reg];
  end

  localparam [2:0] S_IDLE = 3'd0, S_A = 3'd1, S_B = 3'd2, S_D = 3'd3, S_M = 3'd4, S_S = 3'd5;
  reg [2:0] st_reg;
  reg [5:0] f_reg;
  reg signed [15:0] a_reg;
  reg signed [16:0] diff_reg;
  /* verilator lint_off UNUSEDSIGNAL */
  reg signed [23:0] prod_reg;  // bits [5:0] fall off the shift, [23:22] off the 16-bit sum
  /* verilator lint_on UNUSEDSIGNAL */
  reg signed [15:0] temp_reg;
  reg done_reg;

  wire signed [16:0] b_ext = {rdata_reg[15], rdata_reg};
  wire signed [16:0] a_ext = {a_reg[15], a_reg};
  wire signed [15:0] prod_shift = prod_reg[21:6];  // >>> 6 (|product| < 2^22)

  always @(posedge clk) begin
    done_reg <= 1'b0;
    case (st_reg)
      S_IDLE:
      if (start) begin
        rd_addr_reg <= {ch, 1'b0, code[11:6]};
        f_reg       <= code[5:0];
        ch_reg      <= ch[0];
        st_reg      <= S_A;
      end
      S_A: begin  // t[i] is being read
        rd_addr_reg <= rd_addr_reg + 8'd1;
        st_reg      <= S_B;
      end
      S_B: begin  // rdata = t[i]; t[i+1] is being read
        a_reg  <= rdata_reg;
        st_reg <= S_D;
      end
      S_D: begin  // rdata = t[i+1]
        diff_reg <= b_ext - a_ext;
        st_reg   <= S_M;
      end
      S_M: begin
        prod_reg <= diff_reg * $signed({1'b0, f_reg});
        st_reg   <= S_S;
      end
      default: begin  // S_S
        temp_reg <= loaded_reg[ch_reg] ? a_reg + prod_shift[15:0] : 16'h8000;
        done_reg <= 1'b1;
        st_reg   <= S_IDLE;
      end
    endcase
    if (rst) begin
      st_reg      <= S_IDLE;
      rd_addr_reg <= 8'd0;
      f_reg       <= 6'd0;
      ch_reg      <= 1'b0;
      a_reg       <= 16'sd0;
      diff_reg    <= 17'sd0;
      prod_reg    <= 24'sd0;
      temp_reg    <= 16'sd0;
      done_reg    <= 1'b0;
    end
  end

  assign temp = temp_reg;
  assign done = done_reg;
  assign busy = (st_reg != S_IDLE);

endmodule

`default_nettype wire
