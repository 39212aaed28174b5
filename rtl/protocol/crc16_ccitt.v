// crc16_ccitt: CRC-16/CCITT-FALSE (docs/protocol.md "Frame"), one byte per clock.
//
// Polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR; check value: the CRC of
// the ASCII bytes "123456789" is 0x29B1.
// Contract
//   en     a byte (data) is folded into the CRC on this clock edge.
//   init   the CRC state before this edge counts as 0xFFFF: with en, data is the first byte of a
//          new message; without en, the register is just cleared to 0xFFFF.
//   crc    registered: the CRC of all bytes folded in since the last init, from the clock after
//          the edge that folded in the last one (latency 1 clock).
// Residue: after a message followed by its own CRC (high byte first) crc is 0x0000, so a
// receiver can fold in the two CRC bytes and compare with zero.
// The byte step is an 8-deep unrolled shift (an XOR tree of at most a few levels per bit).
// rst is synchronous, active high (crc = 0xFFFF).
`default_nettype none

module crc16_ccitt (
    input  wire        clk,
    input  wire        rst,
    input  wire        init,
    input  wire        en,
    input  wire [ 7:0] data,
    output wire [15:0] crc
);

  reg [15:0] crc_reg;

  // The byte update is formed in block-local regs inside the en branch (the same logic as a
  // function call there; a simulator evaluates it only on the clocks a byte is taken).
  always @(posedge clk) begin : upd
    reg [15:0] x;
    integer i;
    if (rst) begin
      crc_reg <= 16'hFFFF;
    end else if (en) begin
      x = (init ? 16'hFFFF : crc_reg) ^ {data, 8'h00};
      for (i = 0; i < 8; i = i + 1) x = x[15] ? ({x[14:0], 1'b0} ^ 16'h1021) : {x[14:0], 1'b0};
      crc_reg <= x;
    end else if (init) begin
      crc_reg <= 16'hFFFF;
    end
  end

  assign crc = crc_reg;

endmodule

`default_nettype wire
