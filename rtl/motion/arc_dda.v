// arc_dda: circular / helical DDA for one ARC segment (docs/motion.md "Arcs", ARC frame in
// docs/protocol.md). The integer reference is models/include/fpgacnc/models/arc_walk.h; this block
// produces the identical edge list.
//
// Walk: 8-connected lattice walk around the centre, coordinates x, y relative to the centre
// (24-bit signed), F = x^2 + y^2 - T (48-bit signed) tracked with adds only. Per move the three
// forward candidates D = (a, b), A = (a, 0), B = (0, b) (a, b: signs of the tangent s*(-y, x); a
// zero component takes the inward sign, and its axial candidate is not offered) are scored by
// |F| after the move; the smallest wins (ties: D, A, B). The target T ramps from R0^2 to R1^2 over
// the first N_RAMP choices (q or q+1 before each, Bresenham remainder r; the first before move 1),
// so the walk lands exactly on the end point. Move cost |x dy - y dx| = |x|+|y| (D), |y| (A), |x| (B).
// The walk takes WALK_CLOCKS = 4 clocks per move: W0 candidate F and |x|, |y|; W1 |F|, F - next
// ramp step, cumulative costs, end-point tests; W2 select; then READY until the path coordinate
// reaches the move's cumulative cost C_k. At most one move every 4 clocks (the host keeps the
// tangential speed below 1/8 step per clock, so this never binds; when it does, `late` is set and
// the move waits, exactly as the reference does).
// Pacing: U (UQ48.48) += V (UQ16.48) every clock; V ramps by A towards V_cruise until
// U >= D*2^48, then towards V_exit (LINE_PROFILE rules, cost units). Move k fires on the first
// READY clock with U[95:48] >= C_k. Z: remainder DDA Rz += V*|DZ| (the products vz_* and az come
// from prep), a step when Rz >= C_TOTAL*2^48: z(c) = min(|DZ|, floor(U(c)|DZ| / (C_TOTAL 2^48))).
// End: the move that reaches the end point, or the first move whose cumulative cost reaches
// C_TOTAL; err when the two do not coincide (inconsistent frame). `ending` is high on that clock:
// a load on the same edge starts the next arc on the next clock (zero gap); that load clears err, so
// a driver that chains reads `end_err` (valid with `ending`) instead.
//
// Interface: `load` is taken when !busy or ending; its clock is the segment's clock -1 (clock 0 is
// the first busy clock in which `run` is high: while `run` is low the block is frozen (the
// executor holds a loaded arc through DIR hold/setup); `stop` (e-stop) makes it idle at once:
// nothing of a stop clock is registered, so no step of a move firing in it reaches the pins).
// nx_dir / ny_dir: the direction of the next X / Y move (the tangent signs of the walk's current
// point), valid while dir_valid (busy, from the second clock of each move); the executor writes
// DIR from them ahead of the step (at the quadrant points, where an axis reverses). Outputs: *_step are one-clock pulses, registered: an event of clock c is
// on the pins on clock c + 1 (fixed latency 1); *_dir are valid with the step and held. `last`
// comes with the final move's step. err / late are sticky until the next load.
// Resources: no multipliers; adders: 96-bit U, Rz (and Rz - C2), Vz +/- Az, each a 48-bit lower
// half with carry-select upper halves; 64-bit V; 48-bit F and cost sums (x3). No carry chain feeds
// another, and the decisions that drive wide selects or enables start no chain longer than 33
// bits: decel, V - V_exit - A >= 0, V_cruise - V - A >= 0 and Z's step (the signs that pick V, Vz
// and Rz) are carry-save sums whose chains are cut in halves with carry select, picked by the
// fraction adds' carries formed from 24-bit halves; U >= C_k (`fire`, which reaches every
// register's load enable through a chained load) from 24-bit halves; the candidates' magnitude
// compares are registered in W1. Timing alone on an iCE40 HX8K: docs/synthesis.md "Block timing".
`default_nettype none

module arc_dda (
    input wire clk,
    input wire rst,

    input wire               load,
    input wire               run,       // advance (the executor's RUN state); frozen when low
    input wire               stop,      // abort: idle after this edge
    input wire               ccw,
    input wire signed [23:0] i_in,      // centre - start
    input wire signed [23:0] j_in,
    input wire signed [23:0] dx_in,     // end - start
    input wire signed [23:0] dy_in,
    input wire signed [31:0] dz_in,     // Z steps over the arc, |dz| < 2^31
    input wire        [23:0] n_ramp,    // >= 1
    input wire signed [47:0] dt_q,      // floor((R1^2 - R0^2) / n_ramp)
    input wire        [23:0] dt_r,      // remainder, 0 <= dt_r < n_ramp
    input wire        [47:0] c_total,
    input wire        [63:0] v_entry,
    input wire        [63:0] v_cruise,
    input wire        [63:0] v_exit,
    input wire        [47:0] acc_a,
    input wire        [47:0] dec_d,
    input wire        [95:0] vz_entry,  // v_entry * |dz|
    input wire        [95:0] vz_cruise,
    input wire        [95:0] vz_exit,
    input wire        [95:0] az,        // acc_a * |dz|

    output wire busy,
    output wire ending,   // this clock's move is the last one
    output wire end_err,  // with ending: the arc ends inconsistently (err will be set)
    output wire x_step,
    output wire x_dir,  // 1: +
    output wire y_step,
    output wire y_dir,
    output wire z_step,
    output wire z_dir,
    output wire last,
    output wire err,
    output wire late,
    output wire dir_valid,  // nx_dir / ny_dir valid
    output wire nx_dir,     // 1: + (the next X move's direction)
    output wire ny_dir
);

  localparam [1:0] W0 = 2'd0, W1 = 2'd1, W2 = 2'd2, READY = 2'd3;

  reg busy_reg;
  reg [1:0] st_reg;
  reg ccw_reg;

  // geometry and ramp
  reg signed [23:0] x_reg, y_reg, x1_reg, y1_reg;
  reg signed [47:0] f_reg;
  reg signed [47:0] q_reg, qp1_reg;
  reg [23:0] r_reg, n_reg, acc_reg, m_reg;
  reg [47:0] ctot_reg, cnext_reg;

  // W0 -> W1
  reg signed [47:0] fa_reg, fb_reg, fd_reg;
  reg va_reg, vb_reg, apos_reg, bpos_reg;
  reg [23:0] ax_reg, ay_reg, axy_reg;
  reg carry_reg;
  reg [23:0] accn_reg;
  // W1 -> W2
  reg le_da_reg, le_db_reg, le_ab_reg;  // |F_D| <= |F_A|, |F_D| <= |F_B|, |F_A| <= |F_B|
  reg e_neg_reg, e_zero_reg;  // W0 -> W1: F_B - F_A = 2 (b y - a x) < 0, = 0
  reg signed [47:0] fa2_reg, fb2_reg, fd2_reg;
  reg [47:0] sa_reg, sb_reg, sd_reg;
  reg exa_reg, ex0_reg, eyb_reg, ey0_reg;
  // W2 -> READY
  reg mvx_reg, mvy_reg;  // the move has an x / y component
  reg pend_end_reg, guard_reg, exact_reg;

  // pacing
  reg [95:0] u_reg;
  reg [63:0] v_reg, vcr_reg, vex_reg;
  reg [47:0] a_reg, d_reg;
  reg [95:0] vz_reg, vzc_reg, vzx_reg, az_reg, rz_reg;
  reg [31:0] nz_reg, zc_reg;
  reg z_due_reg, zdir_reg;

  // outputs
  reg xs_reg, xd_reg, ys_reg, yd_reg, zs_reg, zd_reg, last_reg, err_reg, late_reg;

  // ---------------- W0, W1, W2 ----------------
  // The candidates, compares and the selection are formed in the clocked block below, in the
  // state's branch whose registers they feed (locals of that block: the same logic as continuous
  // assignments, and a simulator evaluates them only in the clocks of that state).
  //
  // W1: |p| <= |q| for the candidates' F, without taking magnitudes: by the signs sp, sq; with
  // equal signs by the sign of q - p (dneg, dzero), known without a wide subtract: F_A - F_D =
  // -(2 b y + 1), F_B - F_D = -(2 a x + 1), F_B - F_A = 2 (b y - a x) (W0); with opposite signs
  // by S = p + q (sneg, szero; no overflow). Zero test of a sum without its carries: p + q = 0
  // (mod 2^48) iff p ^ q == (p | q) << 1.
  function mag_le;
    input sp, sq, dneg, dzero, sneg, szero;
    mag_le = (sp == sq) ? (sp ? (dneg || dzero) : !dneg) : (sp ? !sneg : (sneg || szero));
  endfunction
  wire        [47:0] u_int = u_reg[95:48];

  // ---------------- pacing ----------------
  // Every compare against a sum of registers is the sign of one carry-save three-operand sum
  // (add3, csa1); the compares of U(c+1) and Rz(c+1) with D*2^48 and C_TOTAL*2^48 are made from
  // the integer parts for carry 0 and 1 out of the 48-bit fraction add, in parallel with it, and
  // that carry picks one (the integer parts are carry-select adds as well). The
  // integer-part compares are not cut at 48 bits: U and Rz stay far below that (U < 2^45 for any
  // arc, Rz < (C_TOTAL + 2^48) 2^48), so this is the same as comparing the 96-bit sums.
  function [65:0] add3;  // p + q + r + c mod 2^66
    input [65:0] p, q, r;
    input [1:0] c;
    reg [65:0] s1, k1, s2, k2, cc;
    begin
      cc   = {64'd0, c};
      s1   = p ^ q ^ r;
      k1   = {(p[64:0] & q[64:0]) | (p[64:0] & r[64:0]) | (q[64:0] & r[64:0]), 1'b0};
      s2   = s1 ^ k1 ^ cc;
      k2   = {(s1[64:0] & k1[64:0]) | (s1[64:0] & cc[64:0]) | (k1[64:0] & cc[64:0]), 1'b0};
      add3 = s2 + k2;
    end
  endfunction
  localparam [65:0] ZERO66 = 66'd0;
  // p + q + r + 1 as two 66-bit operands (carry-save; the + 1 in the free bit 0 of the carries)
  function [131:0] csa1;
    input [65:0] p, q, r;
    csa1 = {p ^ q ^ r, (p[64:0] & q[64:0]) | (p[64:0] & r[64:0]) | (q[64:0] & r[64:0]), 1'b1};
  endfunction
  // sign of s + k + 1 (66 bits): the carry chain in two 33-bit halves, the low half's carry picks
  // the high half's sum for carry 0 or 1 (the + 1 sums as {a, 1} + {b, 1}: one chain each)
  function sgn66p1;
    input [131:0] sk;
    /* verilator lint_off UNUSEDSIGNAL */
    reg [34:0] lo;  // only the carry out and the signs are read
    reg [32:0] h0;
    reg [33:0] h1;
    /* verilator lint_on UNUSEDSIGNAL */
    begin
      lo = {1'b0, sk[98:66], 1'b1} + {1'b0, sk[32:0], 1'b1};
      h0 = sk[131:99] + sk[65:33];
      h1 = {sk[131:99], 1'b1} + {sk[65:33], 1'b1};
      sgn66p1 = lo[34] ? h1[33] : h0[32];
    end
  endfunction
  // 48-bit fields in 66 bits; a sum of them with one negated field is a 50-bit signed value,
  // so bit 49 is its sign and [47:0] its value mod 2^48 (the upper bits are not read). The sums
  // are computed in the clocked block below, in the branch whose registers they feed (locals of
  // that block: the same logic as continuous assignments, and a simulator evaluates them only on
  // the clocks the branch runs).

  // U_int >= C_k from its 24-bit halves (two short chains in parallel instead of one 48-bit one:
  // fire feeds the load enable of every register through `take`)
  wire               u_ge_c = (u_int[47:24] > cnext_reg[47:24]) ||
                              ((u_int[47:24] == cnext_reg[47:24]) && (u_int[23:0] >= cnext_reg[23:0]));
  wire               fire = busy_reg && run && (st_reg == READY) && u_ge_c;
  wire               end_w = fire && (pend_end_reg || guard_reg);
  wire               take = load && !stop && (!busy_reg || end_w);


  always @(posedge clk) begin : seq
    // pacing sums (see above); only some bits of the 66-bit ones are read
    /* verilator lint_off UNUSEDSIGNAL */
    reg [65:0] u_i66, v_i66, rz_i66, vz_i66;
    reg [65:0] u_hi0, u_hi1, rz_hi0, rz_hi1;
    reg [49:0] rcs_s, rcs_k;
    reg [26:0] rlo1;
    reg [25:0] rlo0, rhi1, rf_h1;
    reg [24:0] rhi0, rf_lo, rf_h0, r_lov, r_hiv;
    reg rcf, r_loc;
    reg [49:0] dcs_s, dcs_k;
    reg [26:0] dlo1;  // of the decel sums only the carries out and the signs are read
    reg [25:0] dlo0, dhi1, uf_h1;
    reg [24:0] dhi0, uf_lo, uf_h0;
    reg [48:0] vzp_h1, vzm_h1;  // [0] not read
    /* verilator lint_on UNUSEDSIGNAL */
    reg [48:0] u_frac, rz_frac;
    reg [95:0] u_next, rz_next, rz_sub;
    reg [63:0] v_plus;
    reg [48:0] vzp_lo, vzm_lo;
    reg [47:0] vzp_h0, vzm_h0;
    reg [95:0] vz_plus, vz_minus;
    reg decel, dec_ok, acc_ok, z_go;
    // W0, W1, W2 (see above); of the sums s_* only the signs are read
    reg x_zero, y_zero, x_neg, y_neg, apos, bpos, e_zero, e_neg, carry_w, ramp;
    reg [47:0] x2, y2, ax2o, by2o, s_sel;
    reg signed [47:0] step_w;
    reg [23:0] ox, oy, acc_sum;
    reg [24:0] ymx, ypx, e_src;
    reg by2_neg, ax2_neg, z_da, z_db, z_ab;
    /* verilator lint_off UNUSEDSIGNAL */
    reg [47:0] s_da, s_db, s_ab;
    reg [25:0] acc_d;  // bit 24 not read
    /* verilator lint_on UNUSEDSIGNAL */
    reg signed [23:0] xa_w, yb_w;
    reg sel_d, sel_a, mx_sel, my_sel;

    xs_reg   <= 1'b0;
    ys_reg   <= 1'b0;
    zs_reg   <= 1'b0;
    last_reg <= 1'b0;
    if (busy_reg && run && !stop) begin  // a stop clock registers nothing (no step after it)
      u_i66   = {18'd0, u_int};
      v_i66   = {50'd0, v_reg[63:48]};
      rz_i66  = {18'd0, rz_reg[95:48]};
      vz_i66  = {18'd0, vz_reg[95:48]};
      u_frac  = {1'b0, u_reg[47:0]} + {1'b0, v_reg[47:0]};
      u_hi0   = add3(u_i66, v_i66, ZERO66, 2'd0);
      u_hi1   = add3(u_i66, v_i66, ZERO66, 2'd1);
      u_next  = {u_frac[48] ? u_hi1[47:0] : u_hi0[47:0], u_frac[47:0]};
      // decel: U_int + V_int - D + (carry of the fraction add) >= 0 (50-bit two's complement),
      // U_int + V_int + ~D + 1 carry-saved into dcs_s + dcs_k; the 50-bit sum's halves for carry 0
      // and 1, the fraction add's carry from its 24-bit halves, all in parallel
      dcs_s   = u_i66[49:0] ^ v_i66[49:0] ^ ~{2'd0, d_reg};
      dcs_k   = {(u_i66[48:0] & v_i66[48:0]) | ((u_i66[48:0] | v_i66[48:0]) & ~{1'b0, d_reg}), 1'b1};
      dlo0    = {1'b0, dcs_s[24:0]} + {1'b0, dcs_k[24:0]};
      dlo1    = {1'b0, dcs_s[24:0], 1'b1} + {1'b0, dcs_k[24:0], 1'b1};
      dhi0    = dcs_s[49:25] + dcs_k[49:25];
      dhi1    = {dcs_s[49:25], 1'b1} + {dcs_k[49:25], 1'b1};
      uf_lo   = {1'b0, u_reg[23:0]} + {1'b0, v_reg[23:0]};
      uf_h0   = {1'b0, u_reg[47:24]} + {1'b0, v_reg[47:24]};
      uf_h1   = {1'b0, u_reg[47:24], 1'b1} + {1'b0, v_reg[47:24], 1'b1};
      decel   = !(((uf_lo[24] ? uf_h1[25] : uf_h0[24]) ? dlo1[26] : dlo0[25]) ? dhi1[25] : dhi0[24]);
      dec_ok  = !sgn66p1(csa1({2'd0, v_reg}, ~{2'd0, vex_reg}, ~{18'd0, a_reg}));  // V - V_exit - A >= 0
      v_plus  = v_reg + {16'd0, a_reg};
      // Vz +/- Az: the 48-bit halves in parallel, the low half's carry picks the high sum
      vzp_lo  = {1'b0, vz_reg[47:0]} + {1'b0, az_reg[47:0]};
      vzm_lo  = {1'b0, vz_reg[47:0]} + {1'b0, ~az_reg[47:0]} + 49'd1;
      // (the + 1 sums as {p, 1} + {q, 1}: one chain, not shared with p + q and a second chain)
      vzp_h0  = vz_reg[95:48] + az_reg[95:48];
      vzp_h1  = {vz_reg[95:48], 1'b1} + {az_reg[95:48], 1'b1};
      vzm_h0  = vz_reg[95:48] + ~az_reg[95:48];
      vzm_h1  = {vz_reg[95:48], 1'b1} + {~az_reg[95:48], 1'b1};
      vz_plus = {vzp_lo[48] ? vzp_h1[48:1] : vzp_h0, vzp_lo[47:0]};
      vz_minus = {vzm_lo[48] ? vzm_h1[48:1] : vzm_h0, vzm_lo[47:0]};
      acc_ok  = !sgn66p1(csa1({2'd0, vcr_reg}, ~{2'd0, v_reg}, ~{18'd0, a_reg}));  // V_cruise - V - A >= 0
      rz_frac = {1'b0, rz_reg[47:0]} + {1'b0, vz_reg[47:0]};
      rz_hi0  = add3(rz_i66, vz_i66, ZERO66, 2'd0);
      rz_hi1  = add3(rz_i66, vz_i66, ZERO66, 2'd1);
      // Rz_int + Vz_int - C + (carry of the fraction add), 50-bit two's complement: sign and
      // value from 25-bit halves as for decel (carry-saved, halves for carry 0 and 1)
      rcs_s   = rz_i66[49:0] ^ vz_i66[49:0] ^ ~{2'd0, ctot_reg};
      rcs_k   = {(rz_i66[48:0] & vz_i66[48:0]) | ((rz_i66[48:0] | vz_i66[48:0]) & ~{1'b0, ctot_reg}),
                 1'b1};
      rlo0    = {1'b0, rcs_s[24:0]} + {1'b0, rcs_k[24:0]};
      rlo1    = {1'b0, rcs_s[24:0], 1'b1} + {1'b0, rcs_k[24:0], 1'b1};
      rhi0    = rcs_s[49:25] + rcs_k[49:25];
      rhi1    = {rcs_s[49:25], 1'b1} + {rcs_k[49:25], 1'b1};
      rf_lo   = {1'b0, rz_reg[23:0]} + {1'b0, vz_reg[23:0]};
      rf_h0   = {1'b0, rz_reg[47:24]} + {1'b0, vz_reg[47:24]};
      rf_h1   = {1'b0, rz_reg[47:24], 1'b1} + {1'b0, vz_reg[47:24], 1'b1};
      rcf     = rf_lo[24] ? rf_h1[25] : rf_h0[24];  // = rz_frac[48]
      r_loc   = rcf ? rlo1[26] : rlo0[25];
      r_lov   = rcf ? rlo1[25:1] : rlo0[24:0];
      r_hiv   = r_loc ? rhi1[25:1] : rhi0;
      rz_next = {rz_frac[48] ? rz_hi1[47:0] : rz_hi0[47:0], rz_frac[47:0]};
      rz_sub  = {r_hiv[22:0], r_lov, rz_frac[47:0]};
      z_go    = !r_hiv[24] && (zc_reg != nz_reg);

      // Z and U/V for the next clock
      zs_reg <= z_due_reg;
      if (z_due_reg) zd_reg <= zdir_reg;  // with the step: a chained load may change zdir_reg
      z_due_reg <= z_go;
      if (z_go) begin
        rz_reg <= rz_sub;
        zc_reg <= zc_reg + 32'd1;
      end else begin
        rz_reg <= rz_next;
      end
      u_reg <= u_next;
      if (decel) begin
        if (dec_ok) begin
          v_reg  <= v_reg - {16'd0, a_reg};
          vz_reg <= vz_minus;
        end else begin
          v_reg  <= vex_reg;
          vz_reg <= vzx_reg;
        end
      end else begin
        if (acc_ok) begin
          v_reg  <= v_plus;
          vz_reg <= vz_plus;
        end else begin
          v_reg  <= vcr_reg;
          vz_reg <= vzc_reg;
        end
      end

      case (st_reg)
        W0: begin  // candidates
          x_zero  = (x_reg == 24'sd0);
          y_zero  = (y_reg == 24'sd0);
          x_neg   = x_reg[23];
          y_neg   = y_reg[23];
          // a = sign(t_x), t_x = ccw ? -y : y; inward (-sign x) when y == 0
          apos    = y_zero ? x_neg : (ccw_reg ? y_neg : !y_neg);
          // b = sign(t_y), t_y = ccw ? x : -x; inward (-sign y) when x == 0
          bpos    = x_zero ? y_neg : (ccw_reg ? !x_neg : x_neg);
          x2      = {{23{x_reg[23]}}, x_reg, 1'b0};
          y2      = {{23{y_reg[23]}}, y_reg, 1'b0};
          // 2ax = ax2o + !apos, 2by = by2o + !bpos (-v = ~v + 1): each candidate F is one sum of
          // registers and a small constant (one carry chain, no negate in front of it)
          ax2o    = apos ? x2 : ~x2;
          by2o    = bpos ? y2 : ~y2;
          // |x| + |y| in one chain: (x ^ sx) + (y ^ sy) + sx + sy
          ox      = x_neg ? ~x_reg : x_reg;
          oy      = y_neg ? ~y_reg : y_reg;
          // b y - a x (F_B - F_A = 2 (b y - a x)): y - x or y + x, negated when b = -1
          ymx     = {y_reg[23], y_reg} - {x_reg[23], x_reg};
          ypx     = {y_reg[23], y_reg} + {x_reg[23], x_reg};
          e_src   = (apos == bpos) ? ymx : ypx;
          e_zero  = (e_src == 25'd0);
          e_neg   = bpos ? e_src[24] : (!e_src[24] && !e_zero);
          acc_sum = acc_reg + r_reg;
          // acc + r - n (26-bit two's complement, one chain): carry when >= 0; then < n_reg: fits
          acc_d   = {2'd0, acc_reg} + {2'd0, r_reg} + {2'b11, ~n_reg} + 26'd1;
          carry_w = !acc_d[25];
          fa_reg    <= f_reg + ax2o + {46'd0, !apos, apos};
          fb_reg    <= f_reg + by2o + {46'd0, !bpos, bpos};
          fd_reg    <= f_reg + ax2o + by2o + {45'd0, 3'd2 + {2'd0, !apos} + {2'd0, !bpos}};
          va_reg    <= !y_zero;
          vb_reg    <= !x_zero;
          apos_reg  <= apos;
          bpos_reg  <= bpos;
          ax_reg    <= x_neg ? -x_reg : x_reg;
          ay_reg    <= y_neg ? -y_reg : y_reg;
          axy_reg   <= ox + oy + {22'd0, x_neg && y_neg, x_neg != y_neg};
          carry_reg <= carry_w;
          e_neg_reg <= e_neg;
          e_zero_reg <= e_zero;
          accn_reg  <= carry_w ? acc_d[23:0] : acc_sum;
          st_reg    <= W1;
        end
        W1: begin  // compares, ramp step, cumulative costs, end-point tests
          step_w  = carry_reg ? qp1_reg : q_reg;
          ramp    = (m_reg < n_reg);
          xa_w    = apos_reg ? x_reg + 24'sd1 : x_reg - 24'sd1;
          yb_w    = bpos_reg ? y_reg + 24'sd1 : y_reg - 24'sd1;
          by2_neg = bpos_reg ? y_reg[23] : (!y_reg[23] && (y_reg != 24'sd0));  // 2 b y < 0
          ax2_neg = apos_reg ? x_reg[23] : (!x_reg[23] && (x_reg != 24'sd0));  // 2 a x < 0
          s_da    = fd_reg + fa_reg;
          s_db    = fd_reg + fb_reg;
          s_ab    = fa_reg + fb_reg;
          z_da    = ((fd_reg ^ fa_reg) == {(fd_reg[46:0] | fa_reg[46:0]), 1'b0});
          z_db    = ((fd_reg ^ fb_reg) == {(fd_reg[46:0] | fb_reg[46:0]), 1'b0});
          z_ab    = ((fa_reg ^ fb_reg) == {(fa_reg[46:0] | fb_reg[46:0]), 1'b0});
          le_da_reg <= mag_le(fd_reg[47], fa_reg[47], !by2_neg, 1'b0, s_da[47], z_da);
          le_db_reg <= mag_le(fd_reg[47], fb_reg[47], !ax2_neg, 1'b0, s_db[47], z_db);
          le_ab_reg <= mag_le(fa_reg[47], fb_reg[47], e_neg_reg, e_zero_reg, s_ab[47], z_ab);
          fa2_reg <= ramp ? fa_reg - step_w : fa_reg;
          fb2_reg <= ramp ? fb_reg - step_w : fb_reg;
          fd2_reg <= ramp ? fd_reg - step_w : fd_reg;
          sa_reg  <= cnext_reg + {24'd0, ay_reg};
          sb_reg  <= cnext_reg + {24'd0, ax_reg};
          sd_reg  <= cnext_reg + {24'd0, axy_reg};
          exa_reg <= (xa_w == x1_reg);
          ex0_reg <= (x_reg == x1_reg);
          eyb_reg <= (yb_w == y1_reg);
          ey0_reg <= (y_reg == y1_reg);
          st_reg  <= W2;
        end
        W2: begin  // select
          ramp    = (m_reg < n_reg);
          xa_w    = apos_reg ? x_reg + 24'sd1 : x_reg - 24'sd1;
          yb_w    = bpos_reg ? y_reg + 24'sd1 : y_reg - 24'sd1;
          sel_d   = (!va_reg || le_da_reg) && (!vb_reg || le_db_reg);
          sel_a   = !sel_d && va_reg && (!vb_reg || le_ab_reg);
          s_sel   = sel_d ? sd_reg : (sel_a ? sa_reg : sb_reg);
          mx_sel  = sel_d || sel_a;
          my_sel  = sel_d || !sel_a;
          mvx_reg <= mx_sel;
          mvy_reg <= my_sel;
          f_reg <= sel_d ? fd2_reg : (sel_a ? fa2_reg : fb2_reg);
          if (mx_sel) x_reg <= xa_w;
          if (my_sel) y_reg <= yb_w;
          if (ramp) begin
            acc_reg <= accn_reg;
            m_reg   <= m_reg + 24'd1;
          end
          cnext_reg <= s_sel;
          pend_end_reg <= (mx_sel ? exa_reg : ex0_reg) && (my_sel ? eyb_reg : ey0_reg);
          // the compares of the selected cost, after the selection (they feed one register each)
          guard_reg <= (s_sel >= ctot_reg);
          exact_reg <= (s_sel == ctot_reg);
          if (u_int >= s_sel) late_reg <= 1'b1;
          st_reg <= READY;
        end
        default: begin  // READY
          if (fire) begin
            xs_reg <= mvx_reg;
            ys_reg <= mvy_reg;
            if (mvx_reg) xd_reg <= apos_reg;
            if (mvy_reg) yd_reg <= bpos_reg;
            if (end_w) begin
              last_reg <= 1'b1;
              busy_reg <= 1'b0;
              if (!(pend_end_reg && exact_reg)) err_reg <= 1'b1;
            end
            st_reg <= W0;
          end
        end
      endcase
    end

    if (take) begin
      busy_reg  <= 1'b1;
      st_reg    <= W0;
      ccw_reg   <= ccw;
      x_reg     <= -i_in;
      y_reg     <= -j_in;
      x1_reg    <= dx_in - i_in;
      y1_reg    <= dy_in - j_in;
      f_reg     <= -dt_q;  // the first ramp step (q: dt_r < n_ramp, no carry) before move 1
      q_reg     <= dt_q;
      qp1_reg   <= dt_q + 48'sd1;
      r_reg     <= dt_r;
      n_reg     <= n_ramp;
      acc_reg   <= dt_r;
      m_reg     <= 24'd1;
      ctot_reg  <= c_total;
      cnext_reg <= 48'd0;
      u_reg     <= 96'd0;
      v_reg     <= v_entry;
      vcr_reg   <= v_cruise;
      vex_reg   <= v_exit;
      a_reg     <= acc_a;
      d_reg     <= dec_d;
      vz_reg    <= vz_entry;
      vzc_reg   <= vz_cruise;
      vzx_reg   <= vz_exit;
      az_reg    <= az;
      rz_reg    <= 96'd0;
      nz_reg    <= dz_in[31] ? -dz_in : dz_in;
      zc_reg    <= 32'd0;
      z_due_reg <= 1'b0;
      zdir_reg  <= !dz_in[31];
      err_reg   <= 1'b0;
      late_reg  <= 1'b0;
    end

    if (stop) busy_reg <= 1'b0;

    if (rst) begin
      busy_reg  <= 1'b0;
      st_reg    <= W0;
      xs_reg    <= 1'b0;
      ys_reg    <= 1'b0;
      zs_reg    <= 1'b0;
      xd_reg    <= 1'b0;
      yd_reg    <= 1'b0;
      zd_reg    <= 1'b0;
      last_reg  <= 1'b0;
      err_reg   <= 1'b0;
      late_reg  <= 1'b0;
      z_due_reg <= 1'b0;
    end
  end

  assign busy   = busy_reg;
  assign ending = end_w;
  assign end_err = end_w && !(pend_end_reg && exact_reg);
  assign x_step = xs_reg;
  assign x_dir  = xd_reg;
  assign y_step = ys_reg;
  assign y_dir  = yd_reg;
  assign z_step = zs_reg;
  assign z_dir  = zd_reg;
  assign last   = last_reg;
  assign err    = err_reg;
  assign late   = late_reg;
  assign dir_valid = busy_reg && (st_reg != W0);
  assign nx_dir = apos_reg;
  assign ny_dir = bpos_reg;

`ifdef FORMAL
  // E-stop: after a stop clock no step (and no `last`) leaves the block until the next load, even
  // when a move fired in the stop clock itself (scripts/formal/arc_stop.ys, k-induction).
  reg f_past_valid = 1'b0;
  reg f_quiet = 1'b0;  // a stop since the last load (as of this clock)
  always @(posedge clk) begin
    f_past_valid <= 1'b1;
    f_quiet      <= (f_quiet || stop) && !take;
    if (rst) f_quiet <= 1'b0;
  end
  always @(*)
    if (f_past_valid && f_quiet) begin
      assert (!x_step && !y_step && !z_step && !last);
      assert (!busy_reg);  // induction invariant: only a load makes the block busy again
    end
`endif

endmodule
