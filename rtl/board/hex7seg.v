// hex7seg: one hexadecimal digit to a DE1-SoC seven-segment display (segments active low,
// bit 0 = segment a ... bit 6 = segment g). Combinational; 'b' and 'd' in lower case.
`default_nettype none

module hex7seg (
    input  wire [3:0] digit,
    output wire [6:0] seg_n
);

  reg [6:0] seg;  // active high, gfedcba
  always @(*) begin
    case (digit)
      4'h0: seg = 7'b0111111;
      4'h1: seg = 7'b0000110;
      4'h2: seg = 7'b1011011;
      4'h3: seg = 7'b1001111;
      4'h4: seg = 7'b1100110;
      4'h5: seg = 7'b1101101;
      4'h6: seg = 7'b1111101;
      4'h7: seg = 7'b0000111;
      4'h8: seg = 7'b1111111;
      4'h9: seg = 7'b1101111;
      4'hA: seg = 7'b1110111;
      4'hB: seg = 7'b1111100;
      4'hC: seg = 7'b0111001;
      4'hD: seg = 7'b1011110;
      4'hE: seg = 7'b1111001;
      default: seg = 7'b1110001;  // F
    endcase
  end

  assign seg_n = ~seg;

endmodule

`default_nettype wire
