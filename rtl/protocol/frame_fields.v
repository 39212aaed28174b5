// frame_fields: the field rules of a v2 frame's payload (docs/protocol.md), for frame_decoder.
//
// Contract
//   en        1-clock strobe: evaluate the rules on this edge. frame_decoder raises it on the edge
//             that takes a frame's last byte (CRC low); payload, LEN and TYPE are complete then
//             and do not change before the frame's CHECK clock.
//   pay       payload bytes, byte i in [8*i+:8]; len the frame's LEN.
//   t_*       the frame's TYPE, decoded by frame_decoder (t_heat: any heater frame, 0 when the
//             build has no heaters; t_lprof, t_arc, t_out are 0 when the build leaves them out).
//   ok        registered: the rules held for the inputs at the last en edge (0 after reset).
//             BAD_FIELD is !ok for a known TYPE with a good LEN.
// Rules (BAD_FIELD otherwise): LINE flag bits [6:2] 0; CONFIG_AXIS axis < N_AXES; LINE_PROFILE
// flag bits [6:2] 0, 1 <= max|steps| < 2^24, V_cruise < 2^47, V_entry <= V_cruise, V_exit <=
// V_cruise, V_exit >= 1, A >= 1 or V_entry >= 1; ARC code 2 or 3, flag bits 7:4 0, plane (bits
// 3:2) 0..2 and 0 when N_AXES < 3, start and end not at the centre, |coordinates| about the
// centre < 2^22, DZ != -2^31 (and DZ = 0 when N_AXES < 3), N_RAMP >= 1, 1 <= C_TOTAL < 2^46,
// V_cruise < 2^63, V_entry and V_exit <= V_cruise, V_exit >= 1, A >= 1 or V_entry >= 1; OUTPUT
// mask != 0, value bit 2 clear and value bits only where the mask is set, fan duty 0
// unless mask bit 2; heater frames channel <= 1 (not HEATER_WATCHDOG), HEATER_CONFIG mode <= 4,
// duty_max and manual <= 0x8000, THERMISTOR_TABLE first <= 64 and first + n <= 65,
// HEATER_SAFETY Tmin < Tmax.
// The rules are formed in block-local regs inside the enabled branch of the clocked block: the
// same logic as continuous assignments, and a simulator evaluates them only on en clocks.
`default_nettype none

`include "fpgacnc_spec.vh"

module frame_fields #(
    parameter N_AXES = 4,
    parameter PB     = 63   // payload bytes held by frame_decoder
) (
    input wire clk,
    input wire rst,
    input wire en,

    input wire [8*PB-1:0] pay,
    input wire [     7:0] len,
    input wire            t_line,
    input wire            t_cfg,
    input wire            t_lprof,
    input wire            t_arc,
    input wire            t_out,
    input wire            t_heat,
    input wire            t_hcfg,
    input wire            t_htab,
    input wire            t_hsaf,
    input wire            t_hwd,

    output wire ok
);

  localparam integer NAX_I = N_AXES;
  localparam [7:0] NAX8 = NAX_I[7:0];
  // Limits of the heater frames and the OUTPUT bits, from the specification.
  localparam integer HEAT_CH_I = `FPGACNC_STATUS_HEATER_CHANNELS;
  localparam integer MODE_MAX_I = `FPGACNC_HEATER_MODES - 1;
  localparam integer TAB_N_I = `FPGACNC_THERMISTOR_ENTRIES;
  localparam [7:0] HEAT_CH = HEAT_CH_I[7:0];  // channels 0 .. HEAT_CH - 1
  localparam [7:0] MODE_MAX = MODE_MAX_I[7:0];
  localparam [7:0] TAB_N = TAB_N_I[7:0];  // thermistor entries 0 .. TAB_N - 1

  // pb(i): payload byte i; be32(i): the big-endian 32-bit field at byte i.
`include "payload_fields.vh"

  // |v| < 2^22 for a 25-bit v (the start, -I / -J, has the same magnitudes as I / J)
  function c22_ok;
    input [24:0] v;
    begin
      c22_ok = (v[24:22] == 3'b000) || (v[24:22] == 3'b111 && v[21:0] != 22'd0);
    end
  endfunction

  reg ok_reg;
  always @(posedge clk) begin : rules
    // LINE_PROFILE
    reg [31:0] s;
    reg p_range, p_moves, prof_ok;
    reg [47:0] p_ve, p_vc, p_vx;
    // ARC
    reg signed [24:0] ci, cj, dx, dy, x1, y1;
    reg [31:0] dz;
    reg [23:0] nramp;
    reg [47:0] ctot, acc;
    reg [63:0] a_ve, a_vc, a_vx;
    reg arc_ok;
    // OUTPUT, heater frames
    reg out_ok, heat_ok;
    reg [15:0] umax, manual;
    reg signed [15:0] tmin, tmax;
    reg [7:0] tab_end;
    integer a;
    if (rst) begin
      ok_reg <= 1'b0;
    end else if (en) begin
      // LINE_PROFILE: step fields from byte 28 (int16 when flag bit 7), sign-extended, 0 for the
      // axes LEN leaves out; every axis |steps| < 2^24 and at least one axis moves.
      p_range = 1'b1;
      p_moves = 1'b0;
      for (a = 0; a < N_AXES; a = a + 1) begin
        s = 32'd0;
        if (pay[7]) begin
          if ({1'b0, len} >= 9'd30 + 9'd2 * a[8:0])
            s = {{16{pay[8*(28+2*a)+7]}}, pay[8*(28+2*a)+:8], pay[8*(29+2*a)+:8]};
        end else begin
          if ({1'b0, len} >= 9'd32 + 9'd4 * a[8:0]) s = be32(28 + 4 * a);
        end
        if (!(s[31:24] == 8'h00 || (s[31:24] == 8'hFF && s[23:0] != 24'd0))) p_range = 1'b0;
        if (s != 32'd0) p_moves = 1'b1;
      end
      p_ve = {pb(2), pb(3), be32(4)};
      p_vc = {pb(8), pb(9), be32(10)};
      p_vx = {pb(14), pb(15), be32(16)};
      prof_ok = (pay[6:2] == 5'd0) && p_range && p_moves && !p_vc[47] && (p_ve <= p_vc) &&
                (p_vx <= p_vc) && (p_vx != 48'd0) && (be32(20) != 32'd0 || p_ve != 48'd0);

      // ARC (63 bytes): I, J, DX, DY (int24) at bytes 2, 5, 8, 11, DZ (int32) at 14, N_RAMP
      // (u24) at 18, C_TOTAL (u48) at 21, V_entry, V_cruise, V_exit (u64) at 27, 35, 43, A (u48)
      // at 51. Flags: bits 1:0 code (2 / 3), bits 3:2 the plane (0 XY, 1 ZX, 2 YZ; ZX and YZ need
      // Z: 3 axes).
      ci    = {pay[23], pb(2), pb(3), pb(4)};
      cj    = {pay[47], pb(5), pb(6), pb(7)};
      dx    = {pay[71], pb(8), pb(9), pb(10)};
      dy    = {pay[95], pb(11), pb(12), pb(13)};
      dz    = be32(14);
      nramp = {pb(18), pb(19), pb(20)};
      ctot  = {pb(21), pb(22), be32(23)};
      a_ve  = {be32(27), be32(31)};
      a_vc  = {be32(35), be32(39)};
      a_vx  = {be32(43), be32(47)};
      acc   = {pb(51), pb(52), be32(53)};
      x1    = dx - ci;  // end relative to the centre
      y1    = dy - cj;
      arc_ok = (pay[7:4] == 4'd0) && (pay[3:2] != 2'd3) && (pay[3:2] == 2'd0 || N_AXES >= 3) &&
               pay[1] && (ci != 25'sd0 || cj != 25'sd0) && (x1 != 25'sd0 || y1 != 25'sd0) &&
               c22_ok(ci) && c22_ok(cj) && c22_ok(x1) && c22_ok(y1) &&
               (dz != 32'h8000_0000) && (N_AXES >= 3 || dz == 32'd0) && (nramp != 24'd0) &&
               (ctot != 48'd0) && (ctot[47:46] == 2'b00) && !a_vc[63] && (a_ve <= a_vc) &&
               (a_vx <= a_vc) && (a_vx != 64'd0) && (acc != 48'd0 || a_ve != 64'd0);

      // OUTPUT: mask (bit 0 flood, 1 mist, 2 fan, 3..6 digital outputs 0..3, 7 laser M4 dynamic
      // power), value (the same bits; 2 reserved), fan duty (used with mask bit 2)
      out_ok = (pb(0) != 8'd0) && ((pb(1) & ~pb(0)) == 8'd0) &&
               !pay[8+`FPGACNC_OUT_FAN_BIT] && (pay[`FPGACNC_OUT_FAN_BIT] || pb(2) == 8'd0);

      // heater frames
      umax    = {pb(14), pb(15)};
      manual  = {pb(18), pb(19)};
      tmin    = {pb(1), pb(2)};
      tmax    = {pb(3), pb(4)};
      tab_end = pb(1) + {1'b0, len[7:1]} - 8'd1;  // first + (LEN - 2) / 2
      heat_ok = (pb(0) < HEAT_CH || t_hwd) &&
                !(t_hcfg && (pb(1) > MODE_MAX || umax > `FPGACNC_DUTY_ONE ||
                             manual > `FPGACNC_DUTY_ONE)) &&
                !(t_htab && (pb(1) >= TAB_N || tab_end > TAB_N)) && !(t_hsaf && tmin >= tmax);

      ok_reg <= !(t_line && pay[6:2] != 5'd0) && !(t_cfg && pb(0) >= NAX8) &&
                !(t_lprof && !prof_ok) && !(t_arc && !arc_ok) && !(t_out && !out_ok) &&
                (!t_heat || heat_ok);
    end
  end

  assign ok = ok_reg;

endmodule

`default_nettype wire
