// prep_arc: segment_prep's ARC arithmetic (docs/protocol.md "ARC", docs/motion.md "Arcs"): from the
// ARC payload to arc_dda's load inputs, and the segment's start (|steps| and directions) for the
// executor's DIR rules. segment_prep sequences it (states AMUL, ADIV, AFIX) and holds the result.
//
// load (the clock segment_prep takes a segment entry): the raw ARC payload (I, J, DX, DY int24,
// DZ int32, N_RAMP u24, C_TOTAL u48, V_entry, V_cruise, V_exit u64, A u48, D u48; I in the top
// bits), ccw = code bit 0 and the plane (in_plane when in_arc, else 0: 0 XY, 1 ZX, 2 YZ) are
// latched.
// AMUL (mul_run, iter = 0..31): iteration 0 loads; iterations 1..31 add bit iter-1 of |x0|, |y0|,
// |x1|, |y1| (shift-add squares, 22 bits, (x0, y0) = (-I, -J), (x1, y1) = (DX - I, DY - J)) and of
// |DZ| (the products V_entry, V_cruise, V_exit, A times |DZ|, 96 bits). Not reset: AMUL always
// starts with the load.
// ADIV (div_run, iter = 0..46): iteration 0 forms dT = R1^2 - R0^2 (its sign and |dT| < 2^45);
// iterations 1..46 a restoring division of |dT| by N_RAMP (one quotient bit each, 25-bit remainder).
// AFIX (fix, one clock): floor division (dt_q, dt_r in [0, N_RAMP)) is registered; fix_* are the
// segment's start, valid in that clock only (x in any other): the walk's u / v axes move (|steps|
// 1) with the tangent signs at the start point (arc_dda's first-move directions, a zero component
// taking the inward sign); the helix axis moves |DZ| in the sign of DZ. fix_trk: the axes whose
// tracked DIR takes fix_dir (u, v, and the helix when DZ != 0); fix_unk: u and v (their DIR at
// the arc's end is not known here).
// arc: arc_dda's load inputs, LSB first: ccw 1, I, J, DX, DY 24 each, DZ 32, N_RAMP 24, dt_q 48,
// dt_r 24, C_TOTAL 48, V_entry, V_cruise, V_exit 64 each, A 48, D 48, V_entry*|DZ|,
// V_cruise*|DZ|, V_exit*|DZ|, A*|DZ| 96 each (945 bits). plane: 0 XY / Z, 1 ZX / Y (u = Z, v = X),
// 2 YZ / X (u = Y, v = Z); an axis the build does not have is not moved.
`default_nettype none

module prep_arc #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire         load,
    input wire         in_arc,    // the entry is an ARC
    input wire [  1:0] in_plane,
    input wire         in_ccw,
    input wire [487:0] in_raw,

    input wire       mul_run,  // segment_prep in AMUL
    input wire       div_run,  // ... in ADIV
    input wire       fix,      // ... in AFIX
    input wire [5:0] iter,     // its iteration

    output wire [           944:0] arc,
    output wire [             1:0] plane,
    output reg  [32*N_AXES-1:0] fix_abs,
    output reg  [    N_AXES-1:0] fix_dir,
    output reg  [    N_AXES-1:0] fix_trk,
    output reg  [    N_AXES-1:0] fix_unk
);

  generate
    if (N_AXES < 1) begin : g_bad_n_axes
      prep_arc_illegal_N_AXES_below_1 u_err ();
    end
  endgenerate

  reg [1:0] plane_reg;  // 0 XY, 1 ZX, 2 YZ
  // the physical axes of the walk's u, v and of the helix
  wire [1:0] ax_u = (plane_reg == 2'd1) ? 2'd2 : (plane_reg == 2'd2) ? 2'd1 : 2'd0;
  wire [1:0] ax_v = (plane_reg == 2'd1) ? 2'd0 : (plane_reg == 2'd2) ? 2'd2 : 2'd1;
  wire [1:0] ax_h = (plane_reg == 2'd1) ? 2'd1 : (plane_reg == 2'd2) ? 2'd0 : 2'd2;
  reg ccw_reg;
  reg [487:0] araw_reg;
  wire signed [23:0] a_i = araw_reg[487:464];
  wire signed [23:0] a_j = araw_reg[463:440];
  wire signed [23:0] a_dx = araw_reg[439:416];
  wire signed [23:0] a_dy = araw_reg[415:392];
  wire [31:0] a_dz = araw_reg[391:360];
  wire [23:0] a_nramp = araw_reg[359:336];
  wire [47:0] a_ctot = araw_reg[335:288];
  wire [63:0] a_ve = araw_reg[287:224];
  wire [63:0] a_vc = araw_reg[223:160];
  wire [63:0] a_vx = araw_reg[159:96];
  wire [47:0] a_acc = araw_reg[95:48];
  wire [47:0] a_dd = araw_reg[47:0];
  // squares (shift-add, 22 bits) and the Z products V*|DZ|, A*|DZ| (31 bits), one bit per clock
  reg [4*44-1:0] sq_mc_reg;  // 4 x 44 bits: |x0|, |y0|, |x1|, |y1|
  reg [4*22-1:0] sq_mp_reg;
  reg [4*44-1:0] sq_reg;
  reg [94:0] zmc_e_reg, zmc_c_reg, zmc_x_reg;
  reg [78:0] zmc_a_reg;
  reg [30:0] zmp_reg;
  reg [95:0] vz_e_reg, vz_c_reg, vz_x_reg, az_reg;
  // dT = R1^2 - R0^2 (|dT| < 2^45), floor division by N_RAMP (restoring, 46 bits)
  reg dneg_reg;
  reg [45:0] dnd_reg;
  reg [24:0] drem_reg;
  reg [45:0] dq_reg;
  reg signed [47:0] dt_q_reg;
  reg [23:0] dt_r_reg;

  always @(posedge clk) begin
    if (load) begin
      plane_reg <= in_arc ? in_plane : 2'd0;
      ccw_reg   <= in_ccw;
      araw_reg  <= in_raw;
    end
    if (rst) plane_reg <= 2'd0;
  end

  // AMUL: the squares and the Z products, each register written by one guarded assignment
  // (docs/architecture.md "Simulation speed").
  always @(posedge clk) begin : amul_seq
    /* verilator lint_off UNUSEDSIGNAL */
    reg signed [24:0] a_x1, a_y1;  // |.| < 2^22: bits 23..22 = sign
    /* verilator lint_on UNUSEDSIGNAL */
    reg [21:0] mag_i, mag_j, mag_x1, mag_y1;  // |.| < 2^22 (decoder rule)
    reg [30:0] mag_z;  // |DZ| < 2^31
    reg [4*44-1:0] sq_n, mc_n;
    reg [4*22-1:0] mp_n;
    reg [94:0] ze_n, zc_n, zx_n;
    reg [78:0] za_n;
    reg [30:0] zp_n;
    reg [95:0] ve_n, vc_n, vx_n, az_n;
    integer k;
    if (mul_run) begin
      if (iter == 6'd0) begin
        a_x1 = {a_dx[23], a_dx} - {a_i[23], a_i};
        a_y1 = {a_dy[23], a_dy} - {a_j[23], a_j};
        mag_i = a_i[23] ? -a_i[21:0] : a_i[21:0];
        mag_j = a_j[23] ? -a_j[21:0] : a_j[21:0];
        mag_x1 = a_x1[24] ? -a_x1[21:0] : a_x1[21:0];
        mag_y1 = a_y1[24] ? -a_y1[21:0] : a_y1[21:0];
        mag_z = a_dz[31] ? -a_dz[30:0] : a_dz[30:0];
        mc_n = {22'd0, mag_y1, 22'd0, mag_x1, 22'd0, mag_j, 22'd0, mag_i};
        mp_n = {mag_y1, mag_x1, mag_j, mag_i};
        sq_n = {4 * 44{1'b0}};
        ze_n = {31'd0, a_ve};
        zc_n = {31'd0, a_vc};
        zx_n = {31'd0, a_vx};
        za_n = {31'd0, a_acc};
        zp_n = mag_z;
        ve_n = 96'd0;
        vc_n = 96'd0;
        vx_n = 96'd0;
        az_n = 96'd0;
      end else begin
        for (k = 0; k < 4; k = k + 1) begin
          sq_n[44*k+:44] = sq_mp_reg[22*k] ? sq_reg[44*k+:44] + sq_mc_reg[44*k+:44]
                                           : sq_reg[44*k+:44];
          mp_n[22*k+:22] = {1'b0, sq_mp_reg[22*k+1+:21]};
          mc_n[44*k+:44] = {sq_mc_reg[44*k+:43], 1'b0};
        end
        ve_n = vz_e_reg;
        vc_n = vz_c_reg;
        vx_n = vz_x_reg;
        az_n = az_reg;
        if (zmp_reg[0]) begin
          ve_n = vz_e_reg + {1'b0, zmc_e_reg};
          vc_n = vz_c_reg + {1'b0, zmc_c_reg};
          vx_n = vz_x_reg + {1'b0, zmc_x_reg};
          az_n = az_reg + {17'd0, zmc_a_reg};
        end
        zp_n = {1'b0, zmp_reg[30:1]};
        ze_n = {zmc_e_reg[93:0], 1'b0};
        zc_n = {zmc_c_reg[93:0], 1'b0};
        zx_n = {zmc_x_reg[93:0], 1'b0};
        za_n = {zmc_a_reg[77:0], 1'b0};
      end
      sq_reg    <= sq_n;
      sq_mp_reg <= mp_n;
      sq_mc_reg <= mc_n;
      zmc_e_reg <= ze_n;
      zmc_c_reg <= zc_n;
      zmc_x_reg <= zx_n;
      zmc_a_reg <= za_n;
      zmp_reg   <= zp_n;
      vz_e_reg  <= ve_n;
      vz_c_reg  <= vc_n;
      vz_x_reg  <= vx_n;
      az_reg    <= az_n;
    end
  end

  // ADIV and AFIX: the operands are formed in the branches that use them.
  always @(posedge clk) begin : adiv_seq
    reg [45:0] r0sq, r1sq;  // R0^2 and R1^2
    reg [25:0] drem_shift, drem_diff;
    reg drem_ge;
    if (div_run) begin
      r0sq = {2'b00, sq_reg[44*0+:44]} + {2'b00, sq_reg[44*1+:44]};
      r1sq = {2'b00, sq_reg[44*2+:44]} + {2'b00, sq_reg[44*3+:44]};
      drem_shift = {drem_reg, dnd_reg[45]};
      drem_diff = drem_shift - {2'b00, a_nramp};
      drem_ge = !drem_diff[25];
      if (iter == 6'd0) begin
        dneg_reg <= (r1sq < r0sq);
        dnd_reg  <= (r1sq < r0sq) ? r0sq - r1sq : r1sq - r0sq;
        drem_reg <= 25'd0;
        dq_reg   <= 46'd0;
      end else begin
        dnd_reg  <= {dnd_reg[44:0], 1'b0};
        drem_reg <= drem_ge ? drem_diff[24:0] : drem_shift[24:0];
        dq_reg   <= {dq_reg[44:0], drem_ge};
      end
    end
    if (fix) begin
      // floor: dT < 0 with a remainder gives q = -Q - 1, r = N_RAMP - R
      if (dneg_reg && drem_reg != 25'd0) begin
        dt_q_reg <= -{2'b00, dq_reg} - 48'sd1;
        dt_r_reg <= a_nramp - drem_reg[23:0];
      end else begin
        dt_q_reg <= dneg_reg ? -{2'b00, dq_reg} : {2'b00, dq_reg};
        dt_r_reg <= drem_reg[23:0];
      end
    end
  end

  // AFIX: the segment's start (x outside AFIX: segment_prep reads it only in that clock)
  integer i;
  always @(*) begin : afix_start
    reg arc_dx0, arc_dy0;  // the tangent signs at the start point
    arc_dx0 = 1'bx;
    arc_dy0 = 1'bx;
    fix_abs = {32 * N_AXES{1'bx}};
    fix_dir = {N_AXES{1'bx}};
    fix_trk = {N_AXES{1'bx}};
    fix_unk = {N_AXES{1'bx}};
    if (fix) begin
      // the tangent signs at the start point (x0, y0) = (-I, -J): arc_dda's first-move
      // directions (a zero component takes the inward sign)
      arc_dx0 = (a_j == 24'sd0) ? !a_i[23] : (ccw_reg ? !a_j[23] : a_j[23]);
      arc_dy0 = (a_i == 24'sd0) ? !a_j[23] : (ccw_reg ? a_i[23] : !a_i[23]);
      fix_abs = {32 * N_AXES{1'b0}};
      fix_dir = {N_AXES{1'b0}};
      fix_trk = {N_AXES{1'b0}};
      fix_unk = {N_AXES{1'b0}};
      // u, v move (first-move directions), the helix axis when DZ != 0 (the decoder allows
      // planes other than XY and a helix only with 3 axes)
      for (i = 0; i < N_AXES; i = i + 1) begin
        if (i == {30'd0, ax_u} || i == {30'd0, ax_v}) begin
          fix_abs[32*i+:32] = 32'd1;
          fix_dir[i] = (i == {30'd0, ax_u}) ? arc_dx0 : arc_dy0;
          fix_trk[i] = 1'b1;
          fix_unk[i] = 1'b1;
        end else if (i == {30'd0, ax_h}) begin
          fix_abs[32*i+:32] = {1'b0, a_dz[31] ? -a_dz[30:0] : a_dz[30:0]};  // |DZ| < 2^31
          fix_dir[i] = !a_dz[31];
          fix_trk[i] = (a_dz != 32'd0);
        end
      end
    end
  end

  assign plane = plane_reg;
  assign arc = {az_reg, vz_x_reg, vz_c_reg, vz_e_reg, a_dd, a_acc, a_vx, a_vc, a_ve, a_ctot,
                dt_r_reg, dt_q_reg, a_nramp, a_dz, a_dy, a_dx, a_j, a_i, ccw_reg};

endmodule

`default_nettype wire
