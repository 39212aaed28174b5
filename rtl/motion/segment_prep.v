// segment_prep: turns command-FIFO entries into segments the executor can run without arithmetic.
// This module is the state machine that sequences the preparation, the entry decode and the LINE /
// v1 arithmetic (divider, clamp, multiplier, T - n); the LINE_PROFILE products are rtl/motion/prep_profile.v,
// the ARC arithmetic rtl/motion/prep_arc.v, the DIR tracking and dir_fast rtl/motion/prep_dir_tracker.v.
//
// Input (s_axis_*): one FIFO entry, width ENTRY_W = `FPGACNC_ENTRY_W + 32*N_AXES (839 for 4 axes),
//   { arc_raw[487:0], arc[0], D[31:0], V_exit[47:0], V_cruise[47:0], V_entry[47:0], prof[0],
//     v2[0], kind[1:0], code[1:0], power[7:0], t[31:0], steps[32*N_AXES-1:0] }
//   arc_raw (ARC entries only, else 0): the ARC payload bytes 2..62 as received, byte 2 in the
//   top bits: I, J, DX, DY int24, DZ int32, N_RAMP u24, C_TOTAL u48, V_entry, V_cruise, V_exit
//   u64, A u48, D u48 (docs/protocol.md "ARC").
//   steps: axis a in [32*a+:32], signed. The profile fields (top 177 bits) are 0 except for
//   LINE_PROFILE.
//   kind 0 MOTION, v2 = 1, prof = 1 (LINE_PROFILE): t = A; V_entry, V_cruise, V_exit, D; steps per
//          axis, |steps| < 2^24, not all 0; the frame decoder has checked the field rules of
//          docs/protocol.md. Prepared as kind PROFILE (below).
//   kind 0 MOTION, v2 = 1, arc = 1 (ARC): code 2 / 3 (CW / CCW), power, arc_raw, t[1:0] the plane
//          (0 XY, 1 ZX, 2 YZ); the decoder has checked the field rules. Prepared as kind ARC
//          (below).
//   kind 0 MOTION, v2 = 0 (v1 move): t = {16'd0, feed}, steps[0] = X, steps[1] = Y (the other
//          axes are ignored: v1 moves X and Y only), power 8'hFF.
//   kind 0 MOTION, v2 = 1 (LINE): t = T, the segment length in clocks; steps per axis.
//   kind 1 NUMERATORS: steps[0] = NUMERATOR_X, steps[1] = NUMERATOR_Y (v1 init or v2 frame).
//   kind 2 DWELL: t = T clocks with no steps, laser off (steps, code and power are ignored).
//   kind 3, v2 = 1 (never written by the decoder): a zero-length segment (T = 0, no steps, code 0)
//          that completes at once, so a counted entry always produces one seg_done.
//   kind 3, v2 = 0 OUTPUT (machine outputs, docs/protocol.md "OUTPUT"): t[23:0] = {mask, value,
//          fan duty}. Not prepared: handed to the executor's output port (m_out_*) in the clock
//          the entry is taken from the FIFO (s_axis_tready and m_out_tvalid high together, only
//          while m_out_tready is high); the block stays idle and takes the next entry on the next
//          edge. So an OUTPUT entry costs one clock of preparation time and no executor time.
// Arithmetic per entry (sequential divider and multiplier, one bit per clock; no `/`, `*`):
//   n_dom = max |steps_a|.
//   v1    : P = NUMERATOR_dom / feed (dominant X if |X| >= |Y| else Y), FEED0_PERIOD when
//           feed = 0, raised to min_period when smaller; T = P * n_dom.
//   v2    : n_dom = 0: P = 0, T as given (T = 0: zero-length). Otherwise P = floor(T / n_dom); if
//           P < min_period then P = min_period, T = n_dom * min_period and `clamped` strobes.
//   DWELL : T as given, P = 0, no steps, code 0, power 0.
//   Every segment: tmn[a] = T - |steps_a| (the DDA's wrap constant).
// NUMERATORS are applied only while the executor is idle (exec_idle) and no prepared segment waits,
// so they never change the timing of a move that is queued or running; init_applied strobes for
// one clock with init_v2 = the entry's v2 bit.
// Direction tracking (prep_dir_tracker): prep keeps, per axis, the DIR level the executor will have when the segment
// being prepared starts (after reset 0 = DIR low; updated for the moving axes of every prepared
// segment). m_axis_dir_fast = 1 iff every moving axis that reverses has
// P >= max(DIR hold, 1) + max(DIR setup, 1); the executor may then start the segment with no gap
// and write the reversing DIR pins during the run (docs/timing.md "Queued segments").
// Latency (fixed, whatever the values): m_axis_tvalid rises PREP_LATENCY clocks after the edge
// that accepts the entry:
//   v1 MOTION       : 68            (DIV 33, CLAMP 1, MUL 33, SUB 1)
//   v2 LINE, DWELL, kind 3: 67 + N_AXES (MAX N_AXES - 1, then as v1; the multiplier always runs)
//   LINE_PROFILE    : 25 + N_AXES  (MAX N_AXES - 1, PMUL 25, PINIT 1)
//   ARC             : 80            (AMUL 32, ADIV 47, AFIX 1)
// The next entry is accepted on the edge after the executor takes the prepared segment.
// PROFILE arithmetic (prep_profile; m_axis_kind = 1): n_dom = max |steps_a| (m_axis_prof_n_dom); per axis the
// exact products V_entry*n_a, V_cruise*n_a, V_exit*n_a (71 bits) and A*n_a (56 bits) by a
// shift-add multiplier over the 24 bits of n_a (all axes and products in parallel: 4*N_AXES
// adders of at most 71 bits); vcma = V_cruise - A, vxpa = V_exit + A; and the first master update
// (profile_gen): U(1) = V_entry, V(1) and op(1) from V(0) = V_entry with "decelerating" = (D == 0)
// (U(1) < 1 step). m_axis_total = 0, m_axis_period = 0, m_axis_dir_fast = 0 (a reversing axis
// always waits DIR hold/setup before a profiled segment), m_axis_tmn = 0.
// ARC arithmetic (prep_arc; m_axis_kind = 2; m_axis_arc = arc_dda's load inputs, LSB first: ccw 1, I, J,
// DX, DY 24 each, DZ 32, N_RAMP 24, dt_q 48, dt_r 24, C_TOTAL 48, V_entry, V_cruise, V_exit 64
// each, A 48, D 48, V_entry*|DZ|, V_cruise*|DZ|, V_exit*|DZ|, A*|DZ| 96 each; 945 bits): shift-add
// squares of |x0|, |y0|, |x1|, |y1| (22 bits each, 4 adders of 44 bits) and the Z products (31 bits
// of |DZ|, 3 adders of 95 bits and one of 79) in parallel, 31 iterations; dT = R1^2 - R0^2 and
// its sign; a restoring divider (46 iterations, 25-bit remainder) gives |dT| / N_RAMP, and floor
// division (dt_r in [0, N_RAMP)) follows in one clock. The plane (m_axis_arc_plane) names the
// physical axes of the walk's u / v and of the helix: XY / Z (0), ZX / Y (1: u = Z, v = X), YZ / X
// (2: u = Y, v = Z). m_axis_steps: u = v = 1 and helix = |DZ| (the axes the arc may move),
// m_axis_dir: u / v the tangent signs at the start (arc_dda's first-move rule), the helix axis the
// sign of DZ: the executor's HOLD/SETUP rule applies at the arc's start. The arc's final u / v
// directions are not known here: dir_fast is 0 for the next segment that moves those axes until
// each has moved in a prepared non-arc segment (unk_reg). The same holds for every axis
// after an abort (e-stop), which drops segments whose DIR was already tracked.
// Output (m_axis_*): one prepared segment, held until accepted.
// Build options (cnc_core passes them): PROFILES = 0 / ARCS = 0 never take the PROFILE / ARC
// path (the prof / arc entry bits are ignored, their registers and states are not generated in
// synthesis: they stay constant and are optimized away); cnc_core then stores neither field in
// the FIFO and the decoder answers LINE_PROFILE / ARC frames as unknown types.
// OUTPUTS = 0: no OUTPUT entries (m_out_tvalid constant 0; a kind-3 entry is prepared as the
// zero-length segment whatever its v2 bit).
// V1_ONLY = 1 (cnc_core's protocol-v1 build; needs PROFILES = ARCS = 0): the entries are v1
// MOTION and NUMERATORS only (v2 = 0, kind 0 / 1), so only the v1 arithmetic is built, narrower,
// with the same results on the same clocks (same latency, same outputs): the divider reads the
// dividend bit of the selected numerator by index, one clock ahead (no shifted copy), and divides by feed_reg
// (16-bit remainder, no divisor register); the multiplier shifts the product right through
// total_reg (the multiplier n_dom in its low half, a 33-bit add of P into the high half: no
// multiplier and 64-bit multiplicand registers, no 64-bit adder); no S_MAX scan, v2 clamp or DWELL
// path; m_axis_tmn is 0 (the executor is built with LEAN_DDA and computes T - n itself from
// m_axis_total and m_axis_steps).
`default_nettype none
`include "fpgacnc_spec.vh"

module segment_prep #(
    parameter N_AXES            = 4,
    parameter PROFILES          = 1,      // 0: no LINE_PROFILE entries (prepared as LINE if any)
    parameter ARCS              = 1,      // 0: no ARC entries (prepared as LINE if any)
    parameter V1_ONLY           = 0,      // 1: only v1 MOTION / NUMERATORS entries (see below)
    parameter OUTPUTS           = 1,      // 0: no OUTPUT entries (see below)
    parameter FEED0_PERIOD      = `FPGACNC_DEF_FEED0_PERIOD,
    // CLK_HZ * 60 / steps/mm at the default clock
    parameter DEFAULT_NUMERATOR = `FPGACNC_DEF_CLK_HZ / `FPGACNC_DEF_STEPS_PER_MM * 60
) (
    input wire clk,
    input wire rst,
    /* verilator lint_off SYMRSVDWORD */
    input wire abort,  // e-stop: drop the entry being prepared or waiting (idle after the edge)
    /* verilator lint_on SYMRSVDWORD */

    input  wire [`FPGACNC_ENTRY_W+32*N_AXES-1:0] s_axis_tdata,
    input  wire                    s_axis_tvalid,
    output wire                    s_axis_tready,

    input wire                  exec_idle,
    input wire [          31:0] min_period,
    input wire [16*N_AXES-1:0] cfg_dir_setup,
    input wire [16*N_AXES-1:0] cfg_dir_hold,

    output wire [           1:0] m_axis_code,
    output wire [           7:0] m_axis_power,
    output wire                  m_axis_v2,
    output wire                  m_axis_dir_fast,  // reversals may run with no gap
    output wire [    N_AXES-1:0] m_axis_dir,       // 1 = positive direction
    output wire [ 32*N_AXES-1:0] m_axis_steps,     // |steps| per axis
    output wire [ 64*N_AXES-1:0] m_axis_tmn,       // T - |steps| per axis
    output wire [          63:0] m_axis_total,     // T, segment length in clocks
    output wire [          31:0] m_axis_period,    // P, dominant step period in clocks (0: none)
    output wire [          15:0] m_axis_feed,      // v1 feed as received (status only), 0 for v2
    output wire [           1:0] m_axis_kind,      // 0 LINE (also DWELL, zero-length), 1 PROFILE
    output wire [          46:0] m_axis_prof_u1,
    output wire [          46:0] m_axis_prof_v1,
    output wire [           1:0] m_axis_prof_op1,
    output wire [          31:0] m_axis_prof_accel,
    output wire [          46:0] m_axis_prof_vcruise,
    output wire [          46:0] m_axis_prof_vexit,
    output wire [          47:0] m_axis_prof_vcma,
    output wire [          47:0] m_axis_prof_vxpa,
    output wire [          31:0] m_axis_prof_decel_at,
    output wire [          23:0] m_axis_prof_n_dom,
    output wire [ 71*N_AXES-1:0] m_axis_prof_v0,
    output wire [ 71*N_AXES-1:0] m_axis_prof_vc,
    output wire [ 71*N_AXES-1:0] m_axis_prof_vx,
    output wire [ 56*N_AXES-1:0] m_axis_prof_acc,
    output wire [           944:0] m_axis_arc,  // ARC (kind 2): arc_dda's load inputs, see below
    output wire [             1:0] m_axis_arc_plane,  // ARC: 0 XY, 1 ZX, 2 YZ
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,

    output wire        m_out_tvalid,  // an OUTPUT entry taken from the FIFO in this clock
    output wire [23:0] m_out_tdata,   // {mask, value, fan duty}
    input  wire        m_out_tready,

    output wire [31:0] numerator_x,
    output wire [31:0] numerator_y,
    output wire        init_applied,  // 1-clock strobe: NUMERATORS applied
    output wire        init_v2,       // valid with init_applied: the entry's v2 bit
    output wire        clamped,       // 1-clock strobe: a v2 T was raised to n_dom*min_period
    output wire        busy           // a segment is being prepared or waiting
);

  localparam SW = 32 * N_AXES;
  localparam [1:0] K_MOTION = `FPGACNC_K_MOTION, K_NUMERATORS = `FPGACNC_K_NUMERATORS,
                   K_DWELL = `FPGACNC_K_DWELL, K_OUTPUT = `FPGACNC_K_OUTPUT;
  localparam [3:0] S_IDLE = 4'd0, S_MAX = 4'd1, S_DIV = 4'd2, S_CLAMP = 4'd3, S_MUL = 4'd4,
                   S_SUB = 4'd5, S_OUT = 4'd6, S_PMUL = 4'd7, S_AMUL = 4'd8, S_ADIV = 4'd9,
                   S_AFIX = 4'd10;
  localparam AXW = (N_AXES > 1) ? $clog2(N_AXES) : 1;
  localparam integer AX_LAST_I = N_AXES - 1;
  localparam [AXW-1:0] AX_LAST = AX_LAST_I[AXW-1:0];

  // entry fields
  wire [SW-1:0] in_steps = s_axis_tdata[SW-1:0];
  wire [`FPGACNC_E_T_W-1:0] in_t = s_axis_tdata[SW+`FPGACNC_E_T+:`FPGACNC_E_T_W];
  wire [`FPGACNC_E_POWER_W-1:0] in_power = s_axis_tdata[SW+`FPGACNC_E_POWER+:`FPGACNC_E_POWER_W];
  wire [`FPGACNC_E_CODE_W-1:0] in_code = s_axis_tdata[SW+`FPGACNC_E_CODE+:`FPGACNC_E_CODE_W];
  wire [`FPGACNC_E_KIND_W-1:0] in_kind = s_axis_tdata[SW+`FPGACNC_E_KIND+:`FPGACNC_E_KIND_W];
  wire in_v2 = s_axis_tdata[SW+`FPGACNC_E_V2];
  wire in_v1_motion = (in_kind == K_MOTION) && !in_v2;
  wire in_out = (OUTPUTS != 0) && (V1_ONLY == 0) && (in_kind == K_OUTPUT) && !in_v2;
  wire in_prof = (PROFILES != 0) && s_axis_tdata[SW+`FPGACNC_E_PROF] && (in_kind == K_MOTION) &&
                 in_v2;
  wire [46:0] in_ve = s_axis_tdata[SW+`FPGACNC_E_V_ENTRY+:47];
  wire [46:0] in_vc = s_axis_tdata[SW+`FPGACNC_E_V_CRUISE+:47];
  wire [46:0] in_vx = s_axis_tdata[SW+`FPGACNC_E_V_EXIT+:47];
  wire [`FPGACNC_E_DECEL_AT_W-1:0] in_d =
      s_axis_tdata[SW+`FPGACNC_E_DECEL_AT+:`FPGACNC_E_DECEL_AT_W];
  wire in_arc = (ARCS != 0) && s_axis_tdata[SW+`FPGACNC_E_ARC] && (in_kind == K_MOTION) && in_v2;
  wire [`FPGACNC_E_ARC_RAW_W-1:0] in_arc_raw =
      s_axis_tdata[SW+`FPGACNC_E_ARC_RAW+:`FPGACNC_E_ARC_RAW_W];

  // ARC (rtl/motion/prep_arc.v), PROFILE (rtl/motion/prep_profile.v) and the DIR tracker (rtl/motion/prep_dir_tracker.v):
  // the kind of the segment being prepared selects the path
  reg arc_reg;
  reg prof_reg;
  wire [32*N_AXES-1:0] arc_fix_abs;  // AFIX: the arc's start
  wire [N_AXES-1:0] arc_fix_dir, arc_fix_trk, arc_fix_unk;

  reg [3:0] state_reg;
  reg [31:0] num_x_reg, num_y_reg;
  reg init_applied_reg, init_v2_reg, clamped_reg;

  reg path_v1_reg;  // v1 arithmetic (NUMERATOR / feed)
  reg v2_reg;
  reg [1:0] code_reg;
  reg [7:0] power_reg;
  reg [N_AXES-1:0] dir_reg;
  reg [SW-1:0] abs_reg;
  reg [15:0] feed_reg;  // v1 feed, 0 otherwise
  reg [31:0] n_dom_reg;
  reg [AXW-1:0] scan_idx_reg;

  // restoring divider (V1_ONLY: the divisor is feed, 16 bits; the remainder is below it)
  localparam integer DW = (V1_ONLY != 0) ? 16 : 32;
  reg [31:0] dividend_reg;  // shifts left; its MSB enters the remainder (not used with V1_ONLY)
  reg [DW-1:0] divisor_reg;  // (not used with V1_ONLY: feed_reg)
  reg [DW-1:0] rem_reg;  // remainder < divisor
  reg dom_y_reg;  // V1_ONLY: Y is the dominant axis (its numerator is the dividend)
  reg div_bit_reg;  // V1_ONLY: the dividend bit of the current iteration
  reg [31:0] quot_reg;
  reg [5:0] iter_reg;

  // shift-add multiplier
  reg [31:0] mplier_reg;
  reg [63:0] mcand_reg;
  reg [63:0] total_reg;

  reg [64*N_AXES-1:0] tmn_reg;


  wire [N_AXES-1:0] moving;
  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_in
      assign moving[a] = (abs_reg[32*a+:32] != 32'd0);
    end
  endgenerate

  // One comparator finds the dominant axis: n_dom_reg starts as |X| and takes each next axis that
  // is strictly larger (X wins a tie). v1 does one step (Y) in the first DIV clock.
  wire [31:0] scan_val = abs_reg[32*scan_idx_reg+:32];
  // V1_ONLY: n_dom is |X| or |Y| by dom_y_reg (no n_dom register); Y wins only if strictly larger
  wire [31:0] abs_x = abs_reg[31:0];
  wire [31:0] abs_y = abs_reg[32*(N_AXES>1?1:0)+:32];
  wire scan_gt = (V1_ONLY != 0) ? (abs_y > abs_x) : (scan_val > n_dom_reg);
  wire [31:0] n_dom = (V1_ONLY != 0) ? (dom_y_reg ? abs_y : abs_x) : n_dom_reg;


  // V1_ONLY: iteration k (1..32) takes dividend bit 32 - k of the dominant numerator, selected
  // one clock ahead into div_bit_reg (the select does not precede the subtract)
  wire [31:0] v1_num = dom_y_reg ? num_y_reg : num_x_reg;
  wire [4:0] v1_bit_next = 5'd31 - iter_reg[4:0];  // in iteration k: the bit of iteration k + 1
  wire div_in = (V1_ONLY != 0) ? div_bit_reg : dividend_reg[31];
  /* verilator lint_off UNUSEDSIGNAL */
  wire [31:0] feed32 = {16'd0, feed_reg};  // V1_ONLY uses the low 16 bits
  /* verilator lint_on UNUSEDSIGNAL */
  wire [DW-1:0] divisor = (V1_ONLY != 0) ? feed32[DW-1:0] : divisor_reg;
  // V1_ONLY multiplier step: total_reg = {high half, multiplier bits not yet used}
  wire [32:0] mul_hi = {1'b0, total_reg[63:32]} + (total_reg[0] ? {1'b0, quot_reg} : 33'd0);

  wire idle_state = (state_reg == S_IDLE);
  wire accept_init = idle_state && (in_kind == K_NUMERATORS) && exec_idle && !abort;
  wire accept_seg = idle_state && (in_kind != K_NUMERATORS) && !in_out && !abort;
  wire accept_out = idle_state && in_out && m_out_tready && !abort;

  // The values one state uses are formed in that state's branch (block-local regs): the same
  // logic as continuous assignments, and a simulator skips them in every other clock.
  integer i;
  always @(posedge clk) begin : fsm
    reg [SW-1:0] abs_in;  // IDLE: |steps| of the entry, masked by kind (v1: X and Y only;
    reg [N_AXES-1:0] dir_in;  // DWELL/kind 3: none), and the directions
    reg [DW:0] rem_shift, rem_diff;  // DIV: the restoring division step
    reg rem_ge;  // rem_shift >= divisor
    init_applied_reg <= 1'b0;
    init_v2_reg      <= 1'b0;
    clamped_reg      <= 1'b0;
    case (state_reg)
      S_IDLE: begin
        if (s_axis_tvalid && accept_init) begin
          num_x_reg        <= in_steps[31:0];
          num_y_reg        <= (N_AXES > 1) ? in_steps[32*(N_AXES>1?1:0)+:32] : 32'd0;
          init_applied_reg <= 1'b1;
          init_v2_reg      <= in_v2;
        end else if (s_axis_tvalid && accept_seg) begin
          for (i = 0; i < N_AXES; i = i + 1) begin
            dir_in[i] = !in_steps[32*i+31];
            abs_in[32*i+:32] = !((in_kind == K_MOTION) && (in_v2 || i < 2)) ? 32'd0 :
                               in_steps[32*i+31] ? ~in_steps[32*i+:32] + 32'd1 : in_steps[32*i+:32];
          end
          path_v1_reg  <= in_v1_motion;
          v2_reg       <= in_v2;
          code_reg     <= (in_kind == K_MOTION) ? in_code : 2'd0;
          power_reg    <= (in_kind == K_MOTION) ? in_power : 8'd0;
          dir_reg      <= dir_in;
          abs_reg      <= abs_in;
          // v2 T goes straight into the divider; v1 loads its numerator in the first DIV clock
          dividend_reg <= (in_kind == K_DWELL || (in_kind == K_MOTION && in_v2)) ? in_t : 32'd0;
          feed_reg     <= in_v1_motion ? in_t[15:0] : 16'd0;
          prof_reg     <= in_prof;
          arc_reg      <= in_arc;
          n_dom_reg    <= abs_in[31:0];
          scan_idx_reg <= {{(AXW - 1) {1'b0}}, 1'b1};
          rem_reg      <= {DW{1'b0}};
          quot_reg     <= 32'd0;
          iter_reg     <= 6'd0;
          // v1: the dominant axis (X or Y) is chosen one clock later; v2: scan the other axes first
          state_reg    <= in_arc ? S_AMUL : (in_v1_motion || V1_ONLY != 0) ? S_DIV : S_MAX;
          iter_reg     <= 6'd0;
        end
      end
      S_MAX: begin
        if (scan_gt) n_dom_reg <= scan_val;
        scan_idx_reg <= scan_idx_reg + 1'b1;
        if (scan_idx_reg == AX_LAST) begin
          state_reg <= prof_reg ? S_PMUL : S_DIV;
          iter_reg  <= 6'd0;
        end
      end
      S_PMUL: begin
        // iteration 0 loads; 1..24 add bit iter-1 of every n_a (the products: pmul_seq below);
        // then PINIT (state S_SUB with prof_reg: vcma, vxpa, V(1), op(1)).
        iter_reg <= iter_reg + 6'd1;
        if (iter_reg == 6'd24) state_reg <= S_SUB;
      end
      S_AMUL: begin
        // iteration 0 loads; 1..31 add bit iter-1 of |x0|, |y0|, |x1|, |y1| (squares) and |DZ|
        // (the products: amul_seq below)
        iter_reg <= iter_reg + 6'd1;
        if (iter_reg == 6'd31) begin
          state_reg <= S_ADIV;
          iter_reg  <= 6'd0;
        end
      end
      S_ADIV: begin
        // iteration 0: |dT| and its sign; 1..46: one quotient bit each (prep_arc)
        if (iter_reg == 6'd0) begin
          iter_reg <= 6'd1;
        end else begin
          iter_reg <= iter_reg + 6'd1;
          if (iter_reg == 6'd46) state_reg <= S_AFIX;
        end
      end
      S_AFIX: begin
        // floor division (prep_arc); the arc's start: u, v and the helix axis (prep_arc), the
        // executor's HOLD/SETUP rules apply at the arc's start (prep_dir_tracker: dir_fast 0)
        abs_reg   <= arc_fix_abs;
        dir_reg   <= arc_fix_dir;
        total_reg <= 64'd0;
        quot_reg  <= 32'd0;
        tmn_reg   <= {64 * N_AXES{1'b0}};
        state_reg <= S_OUT;
      end
      S_DIV: begin
        if (iter_reg == 6'd0) begin
          if (V1_ONLY != 0) begin
            dom_y_reg   <= scan_gt;
            div_bit_reg <= scan_gt ? num_y_reg[31] : num_x_reg[31];
          end else if (path_v1_reg) begin
            dividend_reg <= scan_gt ? num_y_reg : num_x_reg;
            divisor_reg  <= feed32[DW-1:0];
            if (scan_gt) n_dom_reg <= scan_val;
          end else begin
            divisor_reg <= n_dom_reg[DW-1:0];
          end
          iter_reg <= 6'd1;
        end else begin
          rem_shift = {rem_reg, div_in};
          rem_diff = rem_shift - {1'b0, divisor};
          rem_ge = !rem_diff[DW];
          if (V1_ONLY == 0) dividend_reg <= {dividend_reg[30:0], 1'b0};
          else div_bit_reg <= v1_num[v1_bit_next];
          rem_reg      <= rem_ge ? rem_diff[DW-1:0] : rem_shift[DW-1:0];
          quot_reg     <= {quot_reg[30:0], rem_ge};
          iter_reg     <= iter_reg + 6'd1;
          if (iter_reg == 6'd32) state_reg <= S_CLAMP;
        end
      end
      S_CLAMP: begin
        // The quotient of a divide by zero (feed 0, n_dom 0) is discarded. The multiplier computes
        // T = P * n_dom + total_reg: v1 and a clamped v2 start from 0; an unclamped v2 from the
        // remainder (P * n_dom + rem = the T given; with n_dom = 0 the remainder is T itself).
        mplier_reg <= n_dom_reg;
        total_reg  <= (V1_ONLY != 0) ? {32'd0, n_dom} : 64'd0;
        if (path_v1_reg || V1_ONLY != 0) begin
          if (feed_reg == 16'd0)
            quot_reg <= (FEED0_PERIOD < min_period) ? min_period : FEED0_PERIOD;
          else if (quot_reg < min_period) quot_reg <= min_period;
        end else if (n_dom_reg == 32'd0) begin
          quot_reg  <= 32'd0;
          total_reg <= {{(64 - DW) {1'b0}}, rem_reg};
        end else if (quot_reg < min_period) begin
          quot_reg    <= min_period;
          clamped_reg <= 1'b1;
        end else begin
          total_reg <= {{(64 - DW) {1'b0}}, rem_reg};
        end
        state_reg <= S_MUL;
        iter_reg  <= 6'd0;
      end
      S_MUL: begin
        if (iter_reg == 6'd0) begin
          mcand_reg    <= {32'd0, quot_reg};
          iter_reg     <= 6'd1;
          scan_idx_reg <= {AXW{1'b0}};  // prep_dir_tracker: the dir_fast check's axis
        end else begin
          if (V1_ONLY != 0) begin
            total_reg <= {mul_hi, total_reg[31:1]};
          end else begin
            if (mplier_reg[0]) total_reg <= total_reg + mcand_reg;
            mplier_reg <= {1'b0, mplier_reg[31:1]};
            mcand_reg  <= {mcand_reg[62:0], 1'b0};
          end
          iter_reg   <= iter_reg + 6'd1;
          if (scan_idx_reg != AX_LAST) scan_idx_reg <= scan_idx_reg + 1'b1;
          if (iter_reg == 6'd32) state_reg <= S_SUB;
        end
      end
      S_SUB: begin
        for (i = 0; i < N_AXES; i = i + 1)
          tmn_reg[64*i+:64] <= (prof_reg || V1_ONLY != 0) ? 64'd0
                                                            : total_reg - {32'd0, abs_reg[32*i+:32]};
        if (prof_reg) begin
          // PINIT: the first master update (prep_profile)
          total_reg <= 64'd0;
          quot_reg  <= 32'd0;
        end
        state_reg <= S_OUT;
      end
      S_OUT: begin
        if (m_axis_tready) state_reg <= S_IDLE;
      end
      default: state_reg <= S_IDLE;
    endcase

    // An abort drops the entry being prepared or waiting (prep_dir_tracker: every axis's DIR
    // unknown again)
    if (abort) state_reg <= S_IDLE;

    if (rst) begin
      state_reg        <= S_IDLE;
      num_x_reg        <= DEFAULT_NUMERATOR;
      num_y_reg        <= DEFAULT_NUMERATOR;
      init_applied_reg <= 1'b0;
      init_v2_reg      <= 1'b0;
      clamped_reg      <= 1'b0;
      path_v1_reg      <= 1'b0;
      v2_reg           <= 1'b0;
      code_reg         <= 2'd0;
      power_reg        <= 8'd0;
      dir_reg          <= {N_AXES{1'b0}};
      abs_reg          <= {SW{1'b0}};
      feed_reg         <= 16'd0;
      n_dom_reg        <= 32'd0;
      scan_idx_reg     <= {AXW{1'b0}};
      dividend_reg     <= 32'd0;
      divisor_reg      <= {DW{1'b0}};
      rem_reg          <= {DW{1'b0}};
      dom_y_reg        <= 1'b0;
      div_bit_reg      <= 1'b0;
      quot_reg         <= 32'd0;
      iter_reg         <= 6'd0;
      mplier_reg       <= 32'd0;
      mcand_reg        <= 64'd0;
      total_reg        <= 64'd0;
      tmn_reg          <= {64 * N_AXES{1'b0}};
      prof_reg         <= 1'b0;
      arc_reg          <= 1'b0;
    end
  end

  wire load_seg = s_axis_tvalid && accept_seg;  // IDLE takes a segment entry

  prep_profile #(
      .N_AXES(N_AXES)
  ) u_prof (
      .clk     (clk),
      .rst     (rst),
      .load    (load_seg),
      .in_ve   (in_ve),
      .in_vc   (in_vc),
      .in_vx   (in_vx),
      .in_accel(in_t),
      .in_d    (in_d),
      .mul_run (state_reg == S_PMUL),
      .iter    (iter_reg),
      .abs     (abs_reg),
      .init    (state_reg == S_SUB && prof_reg),
      .u1      (m_axis_prof_u1),
      .v1      (m_axis_prof_v1),
      .op1     (m_axis_prof_op1),
      .accel   (m_axis_prof_accel),
      .vcruise (m_axis_prof_vcruise),
      .vexit   (m_axis_prof_vexit),
      .vcma    (m_axis_prof_vcma),
      .vxpa    (m_axis_prof_vxpa),
      .decel_at(m_axis_prof_decel_at),
      .v0      (m_axis_prof_v0),
      .vc      (m_axis_prof_vc),
      .vx      (m_axis_prof_vx),
      .acc     (m_axis_prof_acc)
  );

  prep_arc #(
      .N_AXES(N_AXES)
  ) u_arc (
      .clk     (clk),
      .rst     (rst),
      .load    (load_seg),
      .in_arc  (in_arc),
      .in_plane(in_t[1:0]),
      .in_ccw  (in_code[0]),
      .in_raw  (in_arc_raw),
      .mul_run (state_reg == S_AMUL),
      .div_run (state_reg == S_ADIV),
      .fix     (state_reg == S_AFIX),
      .iter    (iter_reg),
      .arc     (m_axis_arc),
      .plane   (m_axis_arc_plane),
      .fix_abs (arc_fix_abs),
      .fix_dir (arc_fix_dir),
      .fix_trk (arc_fix_trk),
      .fix_unk (arc_fix_unk)
  );

  prep_dir_tracker #(
      .N_AXES(N_AXES)
  ) u_dirtrk (
      .clk          (clk),
      .rst          (rst),
      .abort        (abort),
      .mul_start    (state_reg == S_MUL && iter_reg == 6'd0),
      .mul_step     (state_reg == S_MUL && iter_reg != 6'd0),
      .sub          (state_reg == S_SUB),
      .afix         (state_reg == S_AFIX),
      .dir          (dir_reg),
      .moving       (moving),
      .prof         (prof_reg),
      .period       (quot_reg),
      .scan_idx     (scan_idx_reg),
      .fix_dir      (arc_fix_dir),
      .fix_trk      (arc_fix_trk),
      .fix_unk      (arc_fix_unk),
      .cfg_dir_setup(cfg_dir_setup),
      .cfg_dir_hold (cfg_dir_hold),
      .dir_fast     (m_axis_dir_fast)
  );

  assign s_axis_tready   = accept_seg || accept_init || accept_out;
  assign m_out_tvalid    = s_axis_tvalid && accept_out;
  assign m_out_tdata     = in_t[23:0];
  assign m_axis_code     = code_reg;
  assign m_axis_power    = power_reg;
  assign m_axis_v2       = v2_reg;
  assign m_axis_dir      = dir_reg;
  assign m_axis_steps    = abs_reg;
  assign m_axis_tmn      = tmn_reg;
  assign m_axis_total    = total_reg;
  assign m_axis_period   = quot_reg;
  assign m_axis_feed     = feed_reg;
  assign m_axis_kind     = arc_reg ? 2'd2 : {1'b0, prof_reg};
  assign m_axis_prof_n_dom    = n_dom_reg[23:0];
  assign m_axis_tvalid   = (state_reg == S_OUT);
  assign numerator_x     = num_x_reg;
  assign numerator_y     = num_y_reg;
  assign init_applied    = init_applied_reg;
  assign init_v2         = init_v2_reg;
  assign clamped         = clamped_reg;
  assign busy            = !idle_state;

endmodule

`default_nettype wire
