// segment_prep: turns command-FIFO entries into segments the executor can run without arithmetic.
//
// Input (s_axis_*): one FIFO entry, width ENTRY_W = 222 + 32*N_AXES (350 for 4 axes),
//   { D[31:0], V_exit[47:0], V_cruise[47:0], V_entry[47:0], prof[0],
//     v2[0], kind[1:0], code[1:0], power[7:0], t[31:0], steps[32*N_AXES-1:0] }
//   steps: axis a in [32*a+:32], signed. The profile fields (top 177 bits) are 0 except for
//   LINE_PROFILE.
//   kind 0 MOTION, v2 = 1, prof = 1 (LINE_PROFILE): t = A; V_entry, V_cruise, V_exit, D; steps per
//          axis, |steps| < 2^24, not all 0; the frame decoder has checked the field rules of
//          docs/protocol.md. Prepared as kind PROFILE (below).
//   kind 0 MOTION, v2 = 0 (v1 move): t = {16'd0, feed}, steps[0] = X, steps[1] = Y (the other
//          axes are ignored: v1 moves X and Y only), power 8'hFF.
//   kind 0 MOTION, v2 = 1 (LINE): t = T, the segment length in clocks; steps per axis.
//   kind 1 NUMERATORS: steps[0] = NUMERATOR_X, steps[1] = NUMERATOR_Y (v1 init or v2 frame).
//   kind 2 DWELL: t = T clocks with no steps, laser off (steps, code and power are ignored).
//   kind 3 (never written by the decoder): a zero-length segment (T = 0, no steps, code 0) that
//          completes at once, so a counted entry always produces one seg_done.
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
// Direction tracking: prep keeps, per axis, the DIR level the executor will have when the segment
// being prepared starts (after reset 0 = DIR low; updated for the moving axes of every prepared
// segment). m_axis_dir_fast = 1 iff every moving axis that reverses has
// P >= max(DIR hold, 1) + max(DIR setup, 1); the executor may then start the segment with no gap
// and write the reversing DIR pins during the run (docs/timing.md "Queued segments").
// Latency (fixed, whatever the values): m_axis_tvalid rises PREP_LATENCY clocks after the edge
// that accepts the entry:
//   v1 MOTION       : 68            (DIV 33, CLAMP 1, MUL 33, SUB 1)
//   v2 LINE, DWELL, kind 3: 67 + N_AXES (MAX N_AXES - 1, then as v1; the multiplier always runs)
//   LINE_PROFILE    : 26 + N_AXES  (MAX N_AXES - 1, PMUL 25, PINIT 1)
// The next entry is accepted on the edge after the executor takes the prepared segment.
// PROFILE arithmetic (m_axis_kind = 1): n_dom = max |steps_a| (m_axis_prof_n_dom); per axis the
// exact products V_entry*n_a, V_cruise*n_a, V_exit*n_a (71 bits) and A*n_a (56 bits) by a
// shift-add multiplier over the 24 bits of n_a (all axes and products in parallel: 4*N_AXES
// adders of at most 71 bits); vcma = V_cruise - A, vxpa = V_exit + A; and the first master update
// (profile_gen): U(1) = V_entry, V(1) and op(1) from V(0) = V_entry with "decelerating" = (D == 0)
// (U(1) < 1 step). m_axis_total = 0, m_axis_period = 0, m_axis_dir_fast = 0 (a reversing axis
// always waits DIR hold/setup before a profiled segment), m_axis_tmn = 0.
// Output (m_axis_*): one prepared segment, held until accepted.
`default_nettype none

module segment_prep #(
    parameter N_AXES            = 4,
    parameter FEED0_PERIOD      = 62_500,
    parameter DEFAULT_NUMERATOR = 18_750_000   // CLK_HZ * 60 / 160 steps/mm at 50 MHz
) (
    input wire clk,
    input wire rst,
    /* verilator lint_off SYMRSVDWORD */
    input wire abort,  // e-stop: drop the entry being prepared or waiting (idle after the edge)
    /* verilator lint_on SYMRSVDWORD */

    input  wire [222+32*N_AXES-1:0] s_axis_tdata,
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
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,

    output wire [31:0] numerator_x,
    output wire [31:0] numerator_y,
    output wire        init_applied,  // 1-clock strobe: NUMERATORS applied
    output wire        init_v2,       // valid with init_applied: the entry's v2 bit
    output wire        clamped,       // 1-clock strobe: a v2 T was raised to n_dom*min_period
    output wire        busy           // a segment is being prepared or waiting
);

  localparam SW = 32 * N_AXES;
  localparam [1:0] K_MOTION = 2'd0, K_NUMERATORS = 2'd1, K_DWELL = 2'd2;
  localparam [2:0] S_IDLE = 3'd0, S_MAX = 3'd1, S_DIV = 3'd2, S_CLAMP = 3'd3, S_MUL = 3'd4,
                   S_SUB = 3'd5, S_OUT = 3'd6, S_PMUL = 3'd7;
  localparam AXW = (N_AXES > 1) ? $clog2(N_AXES) : 1;
  localparam integer AX_LAST_I = N_AXES - 1;
  localparam [AXW-1:0] AX_LAST = AX_LAST_I[AXW-1:0];

  // entry fields
  wire [SW-1:0] in_steps = s_axis_tdata[SW-1:0];
  wire [31:0] in_t = s_axis_tdata[SW+31:SW];
  wire [7:0] in_power = s_axis_tdata[SW+39:SW+32];
  wire [1:0] in_code = s_axis_tdata[SW+41:SW+40];
  wire [1:0] in_kind = s_axis_tdata[SW+43:SW+42];
  wire in_v2 = s_axis_tdata[SW+44];
  wire in_v1_motion = (in_kind == K_MOTION) && !in_v2;
  wire in_prof = s_axis_tdata[SW+45] && (in_kind == K_MOTION) && in_v2;
  wire [46:0] in_ve = s_axis_tdata[SW+46+:47];
  wire [46:0] in_vc = s_axis_tdata[SW+94+:47];
  wire [46:0] in_vx = s_axis_tdata[SW+142+:47];
  wire [31:0] in_d = s_axis_tdata[SW+190+:32];

  localparam [1:0] OP_INC = 2'd0, OP_DEC = 2'd1, OP_CRU = 2'd2, OP_EXIT = 2'd3;
  // profile registers
  reg prof_reg;
  reg [46:0] ve_reg, vc_reg, vx_reg;
  reg [31:0] pa_reg, d_reg;
  reg [46:0] v1_reg;
  reg [1:0] op1_reg;
  reg [47:0] vcma_reg, vxpa_reg;
  reg [70:0] mc_ve_reg, mc_vc_reg, mc_vx_reg;  // shifted multiplicands
  reg [55:0] mc_a_reg;
  reg [24*N_AXES-1:0] pm_reg;  // per-axis multipliers (n_a), shifted right
  reg [71*N_AXES-1:0] p_v0_reg, p_vc_reg, p_vx_reg;
  reg [56*N_AXES-1:0] p_a_reg;

  reg [2:0] state_reg;
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

  // restoring divider
  reg [31:0] dividend_reg;  // shifts left; its MSB enters the remainder
  reg [31:0] divisor_reg;
  reg [31:0] rem_reg;  // remainder < divisor
  reg [31:0] quot_reg;
  reg [5:0] iter_reg;

  // shift-add multiplier
  reg [31:0] mplier_reg;
  reg [63:0] mcand_reg;
  reg [63:0] total_reg;

  reg [64*N_AXES-1:0] tmn_reg;

  // direction tracking and dir_fast
  reg [N_AXES-1:0] dir_track_reg;  // DIR when the segment being prepared starts
  reg [N_AXES-1:0] rev_reg;  // moving axes that reverse
  reg fast_reg;  // no reversing axis checked so far has P < hold' + setup'
  reg chk_rev_reg;  // the axis in chk_hs_reg reverses
  reg [16:0] chk_hs_reg;  // max(hold,1) + max(setup,1) of one axis
  reg dir_fast_reg;

  // |steps| and direction of the entry, masked by kind (v1: X and Y only; DWELL/kind 3: none)
  wire [SW-1:0] abs_in;
  wire [N_AXES-1:0] dir_in;
  wire [N_AXES-1:0] moving;
  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_in
      wire [31:0] s = in_steps[32*a+:32];
      wire use_axis = (in_kind == K_MOTION) && (in_v2 || a < 2);
      wire [31:0] mag = s[31] ? (~s + 32'd1) : s;
      assign abs_in[32*a+:32] = use_axis ? mag : 32'd0;
      assign dir_in[a] = !s[31];
      assign moving[a] = (abs_reg[32*a+:32] != 32'd0);
    end
  endgenerate

  // One comparator finds the dominant axis: n_dom_reg starts as |X| and takes each next axis that
  // is strictly larger (X wins a tie). v1 does one step (Y) in the first DIV clock.
  wire [31:0] scan_val = abs_reg[32*scan_idx_reg+:32];
  wire scan_gt = (scan_val > n_dom_reg);

  // dir_fast: the axes are checked one per clock during the multiplier's iterations (two stages:
  // hold' + setup' of axis scan_idx_reg into chk_hs_reg, then the compare with P).
  wire [15:0] chk_hold = cfg_dir_hold[16*scan_idx_reg+:16];
  wire [15:0] chk_setup = cfg_dir_setup[16*scan_idx_reg+:16];
  wire [16:0] chk_hs = {1'b0, (chk_hold == 16'd0) ? 16'd1 : chk_hold} +
                       {1'b0, (chk_setup == 16'd0) ? 16'd1 : chk_setup};

  wire [32:0] rem_shift = {rem_reg, dividend_reg[31]};
  wire [32:0] rem_diff = rem_shift - {1'b0, divisor_reg};
  wire rem_ge = !rem_diff[32];  // rem_shift >= divisor

  wire idle_state = (state_reg == S_IDLE);
  wire accept_init = idle_state && (in_kind == K_NUMERATORS) && exec_idle && !abort;
  wire accept_seg = idle_state && (in_kind != K_NUMERATORS) && !abort;

  integer i;
  always @(posedge clk) begin
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
          ve_reg       <= in_ve;
          vc_reg       <= in_vc;
          vx_reg       <= in_vx;
          pa_reg       <= in_t;
          d_reg        <= in_d;
          n_dom_reg    <= abs_in[31:0];
          scan_idx_reg <= {{(AXW - 1) {1'b0}}, 1'b1};
          rem_reg      <= 32'd0;
          quot_reg     <= 32'd0;
          iter_reg     <= 6'd0;
          // v1: the dominant axis (X or Y) is chosen one clock later; v2: scan the other axes first
          state_reg    <= in_v1_motion ? S_DIV : S_MAX;
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
        // iteration 0 loads; 1..24 add bit iter-1 of every n_a; then PINIT (state S_SUB with
        // prof_reg: vcma, vxpa, V(1), op(1)).
        if (iter_reg == 6'd0) begin
          mc_ve_reg <= {24'd0, ve_reg};
          mc_vc_reg <= {24'd0, vc_reg};
          mc_vx_reg <= {24'd0, vx_reg};
          mc_a_reg  <= {24'd0, pa_reg};
          for (i = 0; i < N_AXES; i = i + 1) pm_reg[24*i+:24] <= abs_reg[32*i+:24];
          p_v0_reg <= {71 * N_AXES{1'b0}};
          p_vc_reg <= {71 * N_AXES{1'b0}};
          p_vx_reg <= {71 * N_AXES{1'b0}};
          p_a_reg  <= {56 * N_AXES{1'b0}};
          iter_reg <= 6'd1;
        end else begin
          for (i = 0; i < N_AXES; i = i + 1) begin
            if (pm_reg[24*i]) begin
              p_v0_reg[71*i+:71] <= p_v0_reg[71*i+:71] + mc_ve_reg;
              p_vc_reg[71*i+:71] <= p_vc_reg[71*i+:71] + mc_vc_reg;
              p_vx_reg[71*i+:71] <= p_vx_reg[71*i+:71] + mc_vx_reg;
              p_a_reg[56*i+:56]  <= p_a_reg[56*i+:56] + mc_a_reg;
            end
            pm_reg[24*i+:24] <= {1'b0, pm_reg[24*i+1+:23]};
          end
          mc_ve_reg <= {mc_ve_reg[69:0], 1'b0};
          mc_vc_reg <= {mc_vc_reg[69:0], 1'b0};
          mc_vx_reg <= {mc_vx_reg[69:0], 1'b0};
          mc_a_reg  <= {mc_a_reg[54:0], 1'b0};
          iter_reg  <= iter_reg + 6'd1;
          if (iter_reg == 6'd24) state_reg <= S_SUB;
        end
      end
      S_DIV: begin
        if (iter_reg == 6'd0) begin
          if (path_v1_reg) begin
            dividend_reg <= scan_gt ? num_y_reg : num_x_reg;
            divisor_reg  <= {16'd0, feed_reg};
            if (scan_gt) n_dom_reg <= scan_val;
          end else begin
            divisor_reg <= n_dom_reg;
          end
          iter_reg <= 6'd1;
        end else begin
          dividend_reg <= {dividend_reg[30:0], 1'b0};
          rem_reg      <= rem_ge ? rem_diff[31:0] : rem_shift[31:0];
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
        total_reg  <= 64'd0;
        if (path_v1_reg) begin
          if (feed_reg == 16'd0)
            quot_reg <= (FEED0_PERIOD < min_period) ? min_period : FEED0_PERIOD;
          else if (quot_reg < min_period) quot_reg <= min_period;
        end else if (n_dom_reg == 32'd0) begin
          quot_reg  <= 32'd0;
          total_reg <= {32'd0, rem_reg};
        end else if (quot_reg < min_period) begin
          quot_reg    <= min_period;
          clamped_reg <= 1'b1;
        end else begin
          total_reg <= {32'd0, rem_reg};
        end
        state_reg <= S_MUL;
        iter_reg  <= 6'd0;
      end
      S_MUL: begin
        if (iter_reg == 6'd0) begin
          mcand_reg    <= {32'd0, quot_reg};
          iter_reg     <= 6'd1;
          rev_reg      <= (dir_reg ^ dir_track_reg) & moving;
          scan_idx_reg <= {AXW{1'b0}};
          fast_reg     <= 1'b1;
          chk_rev_reg  <= 1'b0;
        end else begin
          if (mplier_reg[0]) total_reg <= total_reg + mcand_reg;
          mplier_reg <= {1'b0, mplier_reg[31:1]};
          mcand_reg  <= {mcand_reg[62:0], 1'b0};
          iter_reg   <= iter_reg + 6'd1;
          // axis k: sum in iteration k + 1, compare in k + 2 (the last axis repeats harmlessly)
          chk_hs_reg  <= chk_hs;
          chk_rev_reg <= rev_reg[scan_idx_reg];
          if (scan_idx_reg != AX_LAST) scan_idx_reg <= scan_idx_reg + 1'b1;
          if (chk_rev_reg && quot_reg < {15'd0, chk_hs_reg}) fast_reg <= 1'b0;
          if (iter_reg == 6'd32) state_reg <= S_SUB;
        end
      end
      S_SUB: begin
        for (i = 0; i < N_AXES; i = i + 1)
          tmn_reg[64*i+:64] <= prof_reg ? 64'd0 : total_reg - {32'd0, abs_reg[32*i+:32]};
        dir_fast_reg  <= fast_reg && !prof_reg;
        if (prof_reg) begin
          // PINIT: the first master update, from V(0) = V_entry; decelerating iff D == 0
          total_reg <= 64'd0;
          quot_reg  <= 32'd0;
          vcma_reg  <= {1'b0, vc_reg} - {16'd0, pa_reg};
          vxpa_reg  <= {1'b0, vx_reg} + {16'd0, pa_reg};
          if (d_reg == 32'd0) begin
            if ({1'b0, ve_reg} >= {1'b0, vx_reg} + {16'd0, pa_reg}) begin
              v1_reg  <= ve_reg - {15'd0, pa_reg};
              op1_reg <= OP_DEC;
            end else begin
              v1_reg  <= vx_reg;
              op1_reg <= OP_EXIT;
            end
          end else begin
            if ({1'b0, ve_reg} + {16'd0, pa_reg} <= {1'b0, vc_reg}) begin
              v1_reg  <= ve_reg + {15'd0, pa_reg};
              op1_reg <= OP_INC;
            end else begin
              v1_reg  <= vc_reg;
              op1_reg <= OP_CRU;
            end
          end
        end
        dir_track_reg <= (dir_track_reg & ~moving) | (dir_reg & moving);
        state_reg     <= S_OUT;
      end
      S_OUT: begin
        if (m_axis_tready) state_reg <= S_IDLE;
      end
      default: state_reg <= S_IDLE;
    endcase

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
      divisor_reg      <= 32'd0;
      rem_reg          <= 32'd0;
      quot_reg         <= 32'd0;
      iter_reg         <= 6'd0;
      mplier_reg       <= 32'd0;
      mcand_reg        <= 64'd0;
      total_reg        <= 64'd0;
      tmn_reg          <= {64 * N_AXES{1'b0}};
      dir_track_reg    <= {N_AXES{1'b0}};
      rev_reg          <= {N_AXES{1'b0}};
      fast_reg         <= 1'b0;
      chk_rev_reg      <= 1'b0;
      chk_hs_reg       <= 17'd0;
      dir_fast_reg     <= 1'b0;
      prof_reg         <= 1'b0;
      ve_reg           <= 47'd0;
      vc_reg           <= 47'd0;
      vx_reg           <= 47'd0;
      pa_reg           <= 32'd0;
      d_reg            <= 32'd0;
      v1_reg           <= 47'd0;
      op1_reg          <= OP_CRU;
      vcma_reg         <= 48'd0;
      vxpa_reg         <= 48'd0;
      mc_ve_reg        <= 71'd0;
      mc_vc_reg        <= 71'd0;
      mc_vx_reg        <= 71'd0;
      mc_a_reg         <= 56'd0;
      pm_reg           <= {24 * N_AXES{1'b0}};
      p_v0_reg         <= {71 * N_AXES{1'b0}};
      p_vc_reg         <= {71 * N_AXES{1'b0}};
      p_vx_reg         <= {71 * N_AXES{1'b0}};
      p_a_reg          <= {56 * N_AXES{1'b0}};
    end
  end

  assign s_axis_tready   = accept_seg || accept_init;
  assign m_axis_code     = code_reg;
  assign m_axis_power    = power_reg;
  assign m_axis_v2       = v2_reg;
  assign m_axis_dir_fast = dir_fast_reg;
  assign m_axis_dir      = dir_reg;
  assign m_axis_steps    = abs_reg;
  assign m_axis_tmn      = tmn_reg;
  assign m_axis_total    = total_reg;
  assign m_axis_period   = quot_reg;
  assign m_axis_feed     = feed_reg;
  assign m_axis_kind     = {1'b0, prof_reg};
  assign m_axis_prof_u1  = ve_reg;
  assign m_axis_prof_v1  = v1_reg;
  assign m_axis_prof_op1 = op1_reg;
  assign m_axis_prof_accel    = pa_reg;
  assign m_axis_prof_vcruise  = vc_reg;
  assign m_axis_prof_vexit    = vx_reg;
  assign m_axis_prof_vcma     = vcma_reg;
  assign m_axis_prof_vxpa     = vxpa_reg;
  assign m_axis_prof_decel_at = d_reg;
  assign m_axis_prof_n_dom    = n_dom_reg[23:0];
  assign m_axis_prof_v0       = p_v0_reg;
  assign m_axis_prof_vc       = p_vc_reg;
  assign m_axis_prof_vx       = p_vx_reg;
  assign m_axis_prof_acc      = p_a_reg;
  assign m_axis_tvalid   = (state_reg == S_OUT);
  assign numerator_x     = num_x_reg;
  assign numerator_y     = num_y_reg;
  assign init_applied    = init_applied_reg;
  assign init_v2         = init_v2_reg;
  assign clamped         = clamped_reg;
  assign busy            = !idle_state;

endmodule

`default_nettype wire
