// entry_pack: the command-FIFO entry of a v1 packet or v2 frame, for frame_decoder (layout:
// docs/architecture.md "Command-FIFO entry").
//
// Contract
//   build     high in the clock the entry is written (frame_decoder's CHECK clock). The entry is
//             defined only then: in any other clock it is don't-care (x), which lets synthesis
//             keep the plain type mux and a simulator skip the packing while no entry is written.
//   v1        the entry is a v1 packet's (is_init: init packet, else motion; code = its first
//             byte's bits 1:0); else a v2 frame's, by the decoded TYPE t_line, t_dwell, t_lprof,
//             t_arc, t_out, else NUMERATORS.
//   pay       payload bytes, byte i in [8*i+:8] (v1: the bytes after the first); len the LEN.
//   entry     {arc_raw[487:0], arc, D[31:0], V_exit[47:0], V_cruise[47:0], V_entry[47:0], prof,
//             v2, kind[1:0], code[1:0], power[7:0], t[31:0], steps[32*N_AXES-1:0]}, the layout
//             and field values of frame_decoder's header (ENTRY_W, BASE_W, PROF_W are its widths:
//             the whole entry, without the LINE_PROFILE and ARC fields, without the ARC fields).
// Combinational; the fields are formed inside the build branch.
`default_nettype none

module entry_pack #(
    parameter N_AXES  = 4,
    parameter PB      = 63,
    parameter ENTRY_W = 711 + 32 * N_AXES,
    parameter BASE_W  = 45 + 32 * N_AXES,
    parameter PROF_W  = 222 + 32 * N_AXES
) (
    input wire            build,
    input wire            v1,
    input wire            is_init,
    input wire [     1:0] code,
    input wire            t_line,
    input wire            t_dwell,
    input wire            t_lprof,
    input wire            t_arc,
    input wire            t_out,
    input wire [     7:0] len,
    input wire [8*PB-1:0] pay,

    output reg [ENTRY_W-1:0] entry
);

  localparam SW = 32 * N_AXES;
  localparam PW = ENTRY_W - BASE_W;

  // pb(i): payload byte i; be32(i): the big-endian 32-bit field at byte i.
`include "payload_fields.vh"

  // Step fields (steps_l: LINE from byte 6, steps_p: LINE_PROFILE from byte 28): int16 (flag bit
  // 7) or int32 per axis, big-endian, sign-extended; axes beyond LEN are 0 (axis a in [32*a+:32]).
  // Formed in the build branch only (defaults 0 outside it).
  always @(*) begin : pack
    reg [SW-1:0] steps_l, steps_p, two;
    reg [487:0] arc_raw;
    integer a, b;
    steps_l = {SW{1'b0}};
    steps_p = {SW{1'b0}};
    two     = {SW{1'b0}};
    arc_raw = 488'd0;
    entry   = {ENTRY_W{1'bx}};
    if (build) begin
      // v1 and NUMERATORS: two int32 fields at bytes 0 and 4 (axes 0 and 1)
      two[63:0] = {be32(4), be32(0)};
      if (v1)
        entry = is_init ? {{PW{1'b0}}, 1'b0, 2'd1, 2'd0, 8'd0, 32'd0, two}
                        : {{PW{1'b0}}, 1'b0, 2'd0, code, 8'hFF, 16'd0, pb(8), pb(9), two};
      else if (t_line) begin
        for (a = 0; a < N_AXES; a = a + 1) begin
          if (pay[7]) begin
            if ({1'b0, len} >= 9'd8 + 9'd2 * a[8:0])
              steps_l[32*a+:32] = {{16{pay[8*(6+2*a)+7]}}, pay[8*(6+2*a)+:8], pay[8*(7+2*a)+:8]};
          end else begin
            if ({1'b0, len} >= 9'd10 + 9'd4 * a[8:0]) steps_l[32*a+:32] = be32(6 + 4 * a);
          end
        end
        entry = {{PW{1'b0}}, 1'b1, 2'd0, pay[1:0], pb(1), be32(2), steps_l};
      end else if (t_dwell) entry = {{PW{1'b0}}, 1'b1, 2'd2, 2'd0, 8'd0, be32(0), {SW{1'b0}}};
      else if (t_lprof) begin
        for (a = 0; a < N_AXES; a = a + 1) begin
          if (pay[7]) begin
            if ({1'b0, len} >= 9'd30 + 9'd2 * a[8:0])
              steps_p[32*a+:32] = {{16{pay[8*(28+2*a)+7]}}, pay[8*(28+2*a)+:8],
                                   pay[8*(29+2*a)+:8]};
          end else begin
            if ({1'b0, len} >= 9'd32 + 9'd4 * a[8:0]) steps_p[32*a+:32] = be32(28 + 4 * a);
          end
        end
        entry = {{(ENTRY_W - PROF_W) {1'b0}}, be32(24), pb(14), pb(15), be32(16), pb(8), pb(9),
                 be32(10), pb(2), pb(3), be32(4), 1'b1, 1'b1, 2'd0, pay[1:0], pb(1), be32(20),
                 steps_p};
      end else if (t_arc) begin
        // payload bytes 2..62 as they are (big-endian, byte 2 in the top bits)
        for (b = 0; b < 61; b = b + 1) arc_raw[8*(60-b)+:8] = pay[8*(b+2)+:8];
        entry = {arc_raw, 1'b1, {(PROF_W - BASE_W) {1'b0}}, 1'b1, 2'd0, pay[1:0], pb(1), 30'd0,
                 pay[3:2], {SW{1'b0}}};
      end else if (t_out)
        entry = {{PW{1'b0}}, 1'b0, 2'd3, 2'd0, 8'd0, 8'd0, pb(0), pb(1), pb(2), {SW{1'b0}}};
      else entry = {{PW{1'b0}}, 1'b1, 2'd1, 2'd0, 8'd0, 32'd0, two};
    end
  end

endmodule

`default_nettype wire
