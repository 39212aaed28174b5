// ltc2308_spi: SPI master for the DE1-SoC's LTC2308 ADC, reading two single-ended unipolar
// channels (CH_A, CH_B) per request (docs/heater.md "Temperature").
//
// Contract
//   start      1-clock strobe: run one read of both channels (ignored while busy).
//   code_a, code_b  12-bit results (straight binary, 1 mV per code), registered, updated on the
//              done edge.
//   done       1-clock strobe: both codes are new.
// Pins: adc_convst, adc_sck, adc_sdi (outputs, registered), adc_sdo (input, two-flop
//   synchronizer). A read is three frames; frame n: CONVST high for CONVST_CLKS clocks, wait until
//   TCONV_CLKS clocks after the CONVST rise (the chip converts; >= tCONV 1.6 us), then 12 SCK
//   cycles, SCK_DIV clocks low then SCK_DIV clocks high each, SCK idle low. SDI carries the 6-bit
//   input word {S/D=1, O/S, S1, S0, UNI=1, SLP=0} MSB first, changed while SCK is low and
//   latched by the chip on SCK rising; the chip shifts SDO on SCK falling and the master samples
//   its synchronized copy on the clock it raises SCK (SDO then stable for SCK_DIV clocks, needs
//   SCK_DIV >= 3). The chip converts the channel named by the previous frame's word: frame 1 names
//   CH_A (its result is dropped), frame 2 returns CH_A and names CH_B, frame 3 returns CH_B.
// Timing per read: start edge -> done high 3 * (TCONV_CLKS + 1 + 24 * SCK_DIV) + 1 clocks later
//   (defaults: 3 * 206 + 1 = 619 clocks, 12.4 us at 50 MHz; measured by the bench). SCK = CLK / (2 * SCK_DIV) (default 5 MHz; the chip allows 40 MHz).
// rst is synchronous, active high (pins low, idle).
`default_nettype none

module ltc2308_spi #(
    parameter CONVST_CLKS = 4,   // CONVST high time (>= 40 ns)
    parameter TCONV_CLKS  = 85,  // CONVST rise to first SCK (>= 1.6 us: 80 clocks at 50 MHz)
    parameter SCK_DIV     = 5,   // clocks per SCK half period (>= 3)
    parameter CH_A        = 0,
    parameter CH_B        = 1
) (
    input wire clk,
    input wire rst,

    input  wire        start,
    output wire [11:0] code_a,
    output wire [11:0] code_b,
    output wire        done,
    output wire        busy,

    output wire adc_convst,
    output wire adc_sck,
    output wire adc_sdi,
    input  wire adc_sdo
);

  localparam [1:0] S_IDLE = 2'd0, S_CONV = 2'd1, S_SHIFT = 2'd2, S_GAP = 2'd3;
  localparam integer CHA_I = CH_A;
  localparam integer CHB_I = CH_B;
  localparam [2:0] CA = CHA_I[2:0];
  localparam [2:0] CB = CHB_I[2:0];
  localparam [5:0] WORD_A = {1'b1, CA[0], CA[2], CA[1], 1'b1, 1'b0};
  localparam [5:0] WORD_B = {1'b1, CB[0], CB[2], CB[1], 1'b1, 1'b0};
  localparam TW = $clog2(TCONV_CLKS + 1);
  localparam integer TC_LAST_I = TCONV_CLKS - 1;
  localparam [TW-1:0] TC_LAST = TC_LAST_I[TW-1:0];
  localparam integer CV_I = CONVST_CLKS;
  localparam [TW-1:0] CV_END = CV_I[TW-1:0];
  localparam DW = $clog2(SCK_DIV + 1);
  localparam integer DIV_LAST_I = SCK_DIV - 1;
  localparam [DW-1:0] DIV_LAST = DIV_LAST_I[DW-1:0];

  reg [1:0] st_reg;
  reg [1:0] frame_reg;  // 0, 1, 2
  reg [TW-1:0] t_reg;
  reg [DW-1:0] d_reg;
  reg [3:0] bit_reg;  // SCK cycle 0..11
  reg sck_reg, convst_reg, sdi_reg;
  reg [11:0] shift_reg;
  reg [4:0] word_reg;  // the input word's bits still to send after the one on SDI
  reg [11:0] code_a_reg, code_b_reg;
  reg done_reg;
  reg sdo_s1_reg, sdo_s2_reg;

  always @(posedge clk) begin
    sdo_s1_reg <= adc_sdo;
    sdo_s2_reg <= sdo_s1_reg;
    done_reg   <= 1'b0;
    case (st_reg)
      S_IDLE:
      if (start) begin
        frame_reg  <= 2'd0;
        st_reg     <= S_CONV;
        t_reg      <= {TW{1'b0}};
        convst_reg <= 1'b1;
      end
      S_CONV: begin
        // t_reg counts clocks since the CONVST rise (CONVST went high on the edge where t = 0).
        if (t_reg == CV_END - 1'b1) convst_reg <= 1'b0;
        if (t_reg == TC_LAST) begin
          st_reg   <= S_SHIFT;
          d_reg    <= {DW{1'b0}};
          bit_reg  <= 4'd0;
          word_reg <= (frame_reg == 2'd1) ? WORD_B[4:0] : WORD_A[4:0];
          sdi_reg  <= (frame_reg == 2'd1) ? WORD_B[5] : WORD_A[5];
        end else begin
          t_reg <= t_reg + 1'b1;
        end
      end
      S_SHIFT: begin  // SCK low for SCK_DIV clocks, then high for SCK_DIV clocks
        d_reg <= (d_reg == DIV_LAST) ? {DW{1'b0}} : d_reg + 1'b1;
        if (d_reg == DIV_LAST) begin
          if (!sck_reg) begin  // rising: sample SDO (stable since the previous falling edge)
            sck_reg   <= 1'b1;
            shift_reg <= {shift_reg[10:0], sdo_s2_reg};
          end else begin  // falling: next SDI bit, or the end of the frame
            sck_reg <= 1'b0;
            bit_reg <= bit_reg + 4'd1;
            sdi_reg  <= word_reg[4];
            word_reg <= {word_reg[3:0], 1'b0};
            if (bit_reg == 4'd11) st_reg <= S_GAP;
          end
        end
      end
      default: begin  // S_GAP: one clock with SCK low before the next CONVST rise
        if (frame_reg == 2'd1) code_a_reg <= shift_reg;
        if (frame_reg == 2'd2) begin
          code_b_reg <= shift_reg;
          done_reg   <= 1'b1;
          st_reg     <= S_IDLE;
        end else begin
          frame_reg  <= frame_reg + 2'd1;
          st_reg     <= S_CONV;
          t_reg      <= {TW{1'b0}};
          convst_reg <= 1'b1;
        end
      end
    endcase
    if (rst) begin
      st_reg     <= S_IDLE;
      frame_reg  <= 2'd0;
      t_reg      <= {TW{1'b0}};
      d_reg      <= {DW{1'b0}};
      bit_reg    <= 4'd0;
      sck_reg    <= 1'b0;
      convst_reg <= 1'b0;
      sdi_reg    <= 1'b0;
      shift_reg  <= 12'd0;
      word_reg   <= 5'd0;
      code_a_reg <= 12'd0;
      code_b_reg <= 12'd0;
      done_reg   <= 1'b0;
      sdo_s1_reg <= 1'b0;
      sdo_s2_reg <= 1'b0;
    end
  end

  assign code_a     = code_a_reg;
  assign code_b     = code_b_reg;
  assign done       = done_reg;
  assign busy       = (st_reg != S_IDLE);
  assign adc_convst = convst_reg;
  assign adc_sck    = sck_reg;
  assign adc_sdi    = sdi_reg;

endmodule

`default_nettype wire
