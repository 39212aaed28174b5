// segment_executor: runs prepared segments on N_AXES axes back to back: at a constant rate (kind
// LINE), with a trapezoidal speed profile (kind PROFILE) or along an arc (kind ARC); DIR hold /
// setup sequencing, laser, positions, machine outputs (docs/timing.md "Queued segments",
// "Profiled segments", "ARC segments"; docs/architecture.md "Code flow in the device").
// This module sequences the segments (state IDLE / HOLD / SETUP / RUN / ZERO, the tick counter,
// laser, seg_start / seg_done), routes an arc's steps by plane and applies OUTPUT entries; the DIR
// targets, pending DIR writes and the DIR setup / post-abort waits are rtl/motion/dir_sequencer.v, each
// axis's DDAs, step_pulse and position rtl/motion/axis_channel.v.
//
// Segment kinds (s_axis_kind, held in kind_reg for the running segment; each kind has its
// generator, its tick gate and its end condition in run_last):
//   0 LINE: constant rate, T clocks (below). Also DWELL and zero-length segments.
//   2 ARC: s_axis_arc from segment_prep: arc_dda (loaded on accept, advancing only in RUN: the
//     arc's clock 0 is tick 1). s_axis_arc_plane routes the walk's u / v steps and DIR and the
//     helix steps to the plane's axes: 0 XY / Z (axes 0, 1 / 2), 1 ZX / Y (2, 0 / 1), 2 YZ / X
//     (1, 2 / 0); below "X / Y" of an arc means its u / v axes. An arc event of clock c raises STEP at edge R + c + 2 (arc_dda's
//     output register, then step_pulse's). The segment lasts c_last + 2 ticks (c_last: the clock
//     of the arc's last move, arc_dda `ending`): its last tick is the clock after the ending one
//     (arc_end_reg), in which only the last move's step request is issued, so, as for every other
//     kind, the arc's last STEP rises on the segment's last edge and a next segment accepted on
//     that tick (zero gap) starts after it. DIR: at the start the usual rules with
//     prep's first-move directions (an arc never uses dir_fast); inside the arc X and Y reverse at
//     the quadrant points: the direction arc_dda announces for the next move is written when the
//     axis's DIR hold has elapsed (see arc_ann); a STEP within DIR setup of that write strobes
//     `violation`. arc_err strobes when an arc ends inconsistently (arc_dda end_err).
//   1 PROFILE: s_axis_prof_* from segment_prep (docs/timing.md "Profiled segments"): profile_gen
//     (the dominant-axis U/V master) and one dda_profile per axis. Tick j (j = 1, 2, ...) is the
//     clock after edge R + j - 1 as for LINE; the axes step in tick j when floor(U(j)*n_i/M)
//     increments, STEP rises at edge R + j. The segment's last tick is the first j with
//     U(j) >= n_dom*2^48 (profile_gen last, from registers). The LINE tick counter is not used.
//     A profiled segment never uses dir_fast (segment_prep sends 0): a reversing axis always
//     takes the HOLD/SETUP path.
// abort (e-stop): on an edge where abort is high the executor drops the running or waiting
// segment and is idle after it (no seg_done for it); laser is low from that clock (combinational
// gate) and no step request is issued in an abort clock, so no further STEP rises (pulses already
// high finish their high time). A DIR write pending is cancelled (no DIR edge in or after an abort
// clock; the next segment that needs the other direction takes the HOLD/SETUP path), and no
// segment is accepted from IDLE until the largest DIR setup setting has passed since the last abort
// clock (a DIR edge just before the abort still gets its setup time).
// step_block (cnc_core's hard limits, rtl/machine/limit_guard.v): an axis whose bit is high issues no step
// request in that clock (its STEP does not rise on the next edge and its position does not
// change); the segment runs on (cnc_core aborts it on the next clock). step_want is the request
// before abort and step_block, for the limit check.
//
// Input (s_axis_*): one segment from segment_prep: code, laser power, v2 bit, dir_fast, per-axis
// direction and |steps|, the per-axis DDA constant T - |steps| and the length T in clocks.
// s_axis_tready = idle, or RUN during the last tick (tick T) of the running segment; it depends on
// registers only. Edge numbers below are rising clock edges; "after edge e" = the clock e..e+1.
//
// Run of a segment with T > 0 starting at edge R: tick c (c = 1..T) is the clock after edge
// R + c - 1; a step on tick c raises STEP at edge R + c (step_pulse adds one register), so the
// k-th STEP rise of an axis with n steps is at R + ceil(k*T/n) and every axis's last one at R + T.
// A 64-bit tick counter (exact for dwells: a segment with T > 0 and no steps runs T ticks) marks
// the last tick; the segment ends on edge R + T.
//
// Accept edge A (s_axis_tvalid && s_axis_tready). A moving axis "reverses" when its direction
// differs from the DIR level the executor has written or will write (dir_sequencer's dir_tgt).
//   - T = 0: completes at once. From idle: seg_done high after A, idle again (a next segment can
//     be accepted on A + 1). Accepted during a last tick (A = R + T of the running one, whose
//     seg_done is high after A): state ZERO for one clock, its seg_done high after A + 1, idle
//     from A + 1 (next accept on A + 2 at the earliest).
//   - Accepted during the last tick of a running segment (A = R + T), no reversing axis, or
//     reversing axes and s_axis_dir_fast: runs with no gap, R' = A (its tick 1 right after A).
//     Each reversing axis gets a "DIR write pending": its DIR pin changes on the first edge
//     >= A + 1 at which its DIR hold has elapsed since its last STEP rise (step_pulse hold_ok).
//     segment_prep's dir_fast guarantees that this comes at least DIR setup before the axis's
//     first step of the new segment (first step >= R' + floor(T'/n_dom) >= R' + hold + setup).
//   - Otherwise with a reversing axis (from idle, or during the last tick without dir_fast):
//     HOLD until every reversing axis's DIR hold has elapsed since its last STEP rise, write DIR
//     (edge D >= A + 1), SETUP, run from R = D + max(largest DIR setup of those axes, 1).
//   - Otherwise (from idle): R = A.
// seg_start is high after edge R (during tick 1); seg_done is high for one clock after the edge on
// which a segment ends (R + T; see T = 0 above), with seg_done_v2 = that segment's v2 bit. When a
// segment is accepted on the last tick of the previous one, the previous one's seg_done and the
// new one's seg_start are high in the same clock.
// Laser: high after edge R until edge R + T for a segment with code != 0 and power != 0; between
// two such segments run back to back it stays high; low in HOLD, SETUP, ZERO and idle.
// position: signed step count per axis, updated on the edge STEP rises.
// Machine outputs (OUTPUT entries, docs/protocol.md "OUTPUT"): s_out_* from segment_prep, handed
// over on an edge H (s_out_tvalid && s_out_tready). Every segment accepted before H precedes the
// OUTPUT in the FIFO, every segment accepted after it follows it. The entry is applied on the
// edge that ends the segment in progress at H: the levels change on its end edge E = R + T (the
// edge of its last STEP rise; the next segment, taken on its last tick, starts with R' = E: no
// gap; a segment still in HOLD / SETUP at H runs first), on A + 1 of a zero-length segment in
// ZERO, and on H itself when the executor is idle at H (or its segment ends on H). Entries
// handed over while one is pending are merged into it (later bits win);
// they are applied together. out_done strobes for one clock after the edge of the change with
// out_done_n = the number of entries applied (segments_done counts each). Levels: coolant_flood,
// coolant_mist, dout[3:0] (mask bits 0, 1, 3..6, value bits the same), fan_duty (mask bit 2,
// the duty byte), laser_dyn (mask bit 7: M4 dynamic laser power, read by machine_outputs'
// laser PWM with power, prof_run, prof_v and prof_vc). abort clears the levels but laser_dyn (a
// mode, not an output: cleared by rst only) and the pending entry (outputs off from the edge after
// the abort clock; cnc_core also gates them at once) and s_out_tready is low in an abort clock.
// Build options (cnc_core passes them): PROFILES = 0 leaves profile_gen and the dda_profile per
// axis out, ARCS = 0 leaves arc_dda and the in-arc DIR checks out; a segment of a kind left out is
// run as LINE (segment_prep never sends one: the decoder answers those frames as unknown types).
`default_nettype none

module segment_executor #(
    parameter N_AXES   = 4,
    parameter PROFILES = 1,  // 0: no PROFILE kind (no profile_gen / dda_profile)
    parameter ARCS     = 1,  // 0: no ARC kind (no arc_dda)
    parameter LEAN_DDA = 0,  // 1: the DDAs compute T - n from s_axis_total (s_axis_tmn unused) and
                             //    keep no steps-left counter (cnc_core's v1 build)
    parameter OUTPUTS  = 1   // 0: no machine outputs (s_out_* ignored, levels constant 0)
) (
    input wire clk,
    input wire rst,

    input  wire [           1:0] s_axis_code,
    input  wire [           7:0] s_axis_power,
    input  wire                  s_axis_v2,
    input  wire                  s_axis_dir_fast,
    input  wire [    N_AXES-1:0] s_axis_dir,
    input  wire [ 32*N_AXES-1:0] s_axis_steps,
    input  wire [ 64*N_AXES-1:0] s_axis_tmn,
    input  wire [          63:0] s_axis_total,
    input  wire [           1:0] s_axis_kind,       // 0 LINE, 1 PROFILE
    input  wire [          46:0] s_axis_prof_u1,     // PROFILE: U(1) = V_entry
    input  wire [          46:0] s_axis_prof_v1,     // V(1)
    input  wire [           1:0] s_axis_prof_op1,    // op(1)
    input  wire [          31:0] s_axis_prof_accel,  // A
    input  wire [          46:0] s_axis_prof_vcruise,
    input  wire [          46:0] s_axis_prof_vexit,
    input  wire [          47:0] s_axis_prof_vcma,   // V_cruise - A
    input  wire [          47:0] s_axis_prof_vxpa,   // V_exit + A
    input  wire [          31:0] s_axis_prof_decel_at,
    input  wire [          23:0] s_axis_prof_n_dom,
    input  wire [ 71*N_AXES-1:0] s_axis_prof_v0,     // per axis V_entry * n_a
    input  wire [ 71*N_AXES-1:0] s_axis_prof_vc,     // V_cruise * n_a
    input  wire [ 71*N_AXES-1:0] s_axis_prof_vx,     // V_exit * n_a
    input  wire [ 56*N_AXES-1:0] s_axis_prof_acc,    // A * n_a
    input  wire [           944:0] s_axis_arc,         // ARC: arc_dda's load inputs (segment_prep)
    input  wire [             1:0] s_axis_arc_plane,   // ARC: 0 XY, 1 ZX, 2 YZ (see below)
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,

    input  wire        s_out_tvalid,  // OUTPUT entry from segment_prep: {mask, value, fan duty}
    input  wire [23:0] s_out_tdata,
    output wire        s_out_tready,

    input wire [16*N_AXES-1:0] cfg_step_high,
    input wire [16*N_AXES-1:0] cfg_step_low,
    input wire [16*N_AXES-1:0] cfg_dir_setup,
    input wire [16*N_AXES-1:0] cfg_dir_hold,

    /* verilator lint_off SYMRSVDWORD */
    input wire abort,  // e-stop: drop everything (see above)
    /* verilator lint_on SYMRSVDWORD */
    input wire adv,  // the motion rate's enable (rtl/motion/feed_rate.v): a RUN clock is a tick
    output wire rapid_seg,  // the segment last accepted has code 0 (feed_rate's target)
    input wire [N_AXES-1:0] step_block,  // 1: no step request of that axis in this clock (limits)
    output wire [N_AXES-1:0] step_want,  // each axis's step request before abort and step_block

    output wire [N_AXES-1:0] step,
    output wire [N_AXES-1:0] dir,
    output wire              laser,

    output wire                 busy,         // a segment is in progress (HOLD, SETUP, RUN, ZERO)
    output wire                 idle,         // not busy and every STEP pulse finished
    output wire                 running,      // RUN: ticks are being issued
    output wire                 seg_start,    // high during tick 1 of a segment
    output wire                 seg_done,     // 1-clock strobe after a segment's end
    output wire                 seg_done_v2,  // valid with seg_done: that segment's v2 bit
    output wire [32*N_AXES-1:0] position,
    output wire                 violation,    // 1-clock strobe: a step came before STEP low time
                                              // (or, in an arc, before its DIR setup)
    output wire                 arc_err,      // 1-clock strobe: an arc ended inconsistently

    output wire        coolant_flood,  // machine outputs (OUTPUT entries)
    output wire        coolant_mist,
    output wire [ 3:0] dout,
    output wire [ 7:0] fan_duty,
    output wire        laser_dyn,      // M4 dynamic laser power (OUTPUT mask bit 7)
    output wire [ 7:0] power,          // the power byte of the segment last accepted
    output wire        prof_run,       // the segment last accepted is a PROFILE
    output wire [46:0] prof_v,         // its V now (profile_gen) and V_cruise
    output wire [46:0] prof_vc,
    output wire        out_done,       // 1-clock strobe after the edge OUTPUT entries took effect
    output wire [15:0] out_done_n      // with out_done: how many entries
);

  localparam [2:0] S_IDLE = 3'd0, S_HOLD = 3'd1, S_SETUP = 3'd2, S_RUN = 3'd3, S_ZERO = 3'd4;
  localparam [1:0] K_LINE = 2'd0, K_PROFILE = 2'd1, K_ARC = 2'd2;

  generate
    if (PROFILES != 0 && PROFILES != 1) begin : g_bad_profiles
      segment_executor_illegal_PROFILES_not_0_or_1 u_err ();
    end
    if (ARCS != 0 && ARCS != 1) begin : g_bad_arcs
      segment_executor_illegal_ARCS_not_0_or_1 u_err ();
    end
    if (ARCS != 0 && N_AXES < 2) begin : g_bad_arc_axes
      segment_executor_illegal_ARCS_need_N_AXES_2 u_err ();
    end
    if (OUTPUTS != 0 && OUTPUTS != 1) begin : g_bad_outputs
      segment_executor_illegal_OUTPUTS_not_0_or_1 u_err ();
    end
  endgenerate

  reg [2:0] state_reg;
  reg [1:0] code_reg;
  reg [1:0] kind_reg;
  reg [7:0] power_reg;
  reg v2_reg;
  reg [63:0] left_reg;  // ticks left including the current one
  reg last_reg;  // the current tick is the last (left_reg == 1)
  reg laser_reg;
  reg seg_start_reg;
  reg seg_done_reg;
  reg seg_done_v2_reg;

  wire [N_AXES-1:0] pulse_idle, pulse_hold_ok, pulse_violation;
  wire [N_AXES-1:0] moving;
  wire prof_last;
  wire [1:0] prof_op;

`ifdef FORMAL
  wire [N_AXES-1:0] f_setup_axes;  // the DIR sequencer's registers, for the invariants below
  wire [15:0] f_setup_cnt, f_settle, f_setup_max;
`endif
  // the DIR sequencer's outputs (rtl/motion/dir_sequencer.v)
  wire [N_AXES-1:0] dir_tgt;  // DIR level written or pending per axis
  wire [N_AXES-1:0] rev;  // moving axes of the input segment that reverse
  wire [N_AXES-1:0] pend;  // DIR write pending
  wire [N_AXES-1:0] dir_wr;
  wire hold_clear, setup_ok, settled, arc_dir_viol;

  wire tick = (state_reg == S_RUN) && adv;
  wire line_tick = tick && (kind_reg == K_LINE);
  wire prof_tick = tick && (kind_reg == K_PROFILE);
  wire arc_tick = tick && (kind_reg == K_ARC);
  wire arc_ending, arc_end_err, arc_xs, arc_ys, arc_dvalid, arc_nx, arc_ny;
  /* verilator lint_off UNUSEDSIGNAL */
  wire arc_zs;  // unused with N_AXES < 3 (the decoder NAKs an ARC with DZ != 0 then)
  /* verilator lint_on UNUSEDSIGNAL */
  // ARC: the clock after arc_dda's ending clock is the segment's last tick (the last move's step
  // request, registered in arc_dda, is issued in it); arc_dda is idle then.
  reg arc_end_reg;
  wire run_last = tick && ((kind_reg == K_PROFILE) ? prof_last :
                           (kind_reg == K_ARC) ? arc_end_reg : last_reg);
  wire ready = !abort && (((state_reg == S_IDLE) && settled) || run_last);
  wire accept = ready && s_axis_tvalid;
  wire prof_in = (PROFILES != 0) && (s_axis_kind == K_PROFILE);
  wire arc_in = (ARCS != 0) && (s_axis_kind == K_ARC);
  wire zero_len = !prof_in && !arc_in && (s_axis_total == 64'd0);
  wire cutting = (s_axis_code != 2'd0) && (s_axis_power != 8'd0);
  wire [N_AXES-1:0] arc_ann;  // ARC: the next X / Y move's direction differs from dir_tgt
  wire [N_AXES-1:0] arc_req;  // ARC: step requests of arc_dda
  // ARC: X / Y reverse inside the arc (at the quadrant points). arc_dda announces the direction of
  // the next X / Y move from the second clock of the move (at least 3 clocks before it can fire);
  // when it differs from dir_tgt a DIR write becomes pending and is done as soon as the axis's
  // DIR hold has elapsed (dir_sequencer). A STEP of the arc whose direction is not on the DIR pin
  // yet, or that comes less than DIR setup after the DIR change, is a timing violation (reported,
  // not delayed; the host keeps arcs slow enough near the quadrant points, docs/protocol.md).

  generate
    if (PROFILES != 0) begin : g_prof
    profile_gen u_prof (
        .clk     (clk),
        .rst     (rst),
        .load    (accept && prof_in),
        .u1      (s_axis_prof_u1),
        .v1      (s_axis_prof_v1),
        .op1     (s_axis_prof_op1),
        .accel   (s_axis_prof_accel),
        .vcruise (s_axis_prof_vcruise),
        .vexit   (s_axis_prof_vexit),
        .vcma    (s_axis_prof_vcma),
        .vxpa    (s_axis_prof_vxpa),
        .decel_at(s_axis_prof_decel_at),
        .n_dom   (s_axis_prof_n_dom),
        .tick    (prof_tick),
        .last    (prof_last),
        .op      (prof_op),
        .v       (prof_v),
        .vcruise_q(prof_vc)
    );
    end else begin : g_noprof
      assign prof_last = 1'b0;
      assign prof_op   = 2'd0;
      assign prof_v    = 47'd0;
      assign prof_vc   = 47'd0;
      // the profile fields are not used without profiles
      wire unused_prof = &{1'b0, s_axis_prof_u1, s_axis_prof_v1, s_axis_prof_op1,
                           s_axis_prof_accel, s_axis_prof_vcruise, s_axis_prof_vexit,
                           s_axis_prof_vcma, s_axis_prof_vxpa, s_axis_prof_decel_at};
    end
  endgenerate

  // arc_dda outputs the executor does not use (DIR comes from nx_dir / ny_dir and the prep's
  // start directions; last / err / late are the bench's)
  /* verilator lint_off UNUSEDSIGNAL */
  wire arc_busy_nc, arc_zd_nc, arc_last_nc, arc_errs_nc, arc_late_nc;
  /* verilator lint_on UNUSEDSIGNAL */
  wire [1:0] arc_sd;  // the direction of the arc's X / Y step on arc_req (1: +)
  generate
    if (ARCS != 0) begin : g_arc
    arc_dda u_arc (
        .clk      (clk),
        .rst      (rst),
        .load     (accept && arc_in),
        .run      (arc_tick),
        .stop     (abort),
        .ccw      (s_axis_arc[0]),
        .i_in     (s_axis_arc[1+:24]),
        .j_in     (s_axis_arc[25+:24]),
        .dx_in    (s_axis_arc[49+:24]),
        .dy_in    (s_axis_arc[73+:24]),
        .dz_in    (s_axis_arc[97+:32]),
        .n_ramp   (s_axis_arc[129+:24]),
        .dt_q     (s_axis_arc[153+:48]),
        .dt_r     (s_axis_arc[201+:24]),
        .c_total  (s_axis_arc[225+:48]),
        .v_entry  (s_axis_arc[273+:64]),
        .v_cruise (s_axis_arc[337+:64]),
        .v_exit   (s_axis_arc[401+:64]),
        .acc_a    (s_axis_arc[465+:48]),
        .dec_d    (s_axis_arc[513+:48]),
        .vz_entry (s_axis_arc[561+:96]),
        .vz_cruise(s_axis_arc[657+:96]),
        .vz_exit  (s_axis_arc[753+:96]),
        .az       (s_axis_arc[849+:96]),
        .busy     (arc_busy_nc),
        .ending   (arc_ending),
        .end_err  (arc_end_err),
        .x_step   (arc_xs),
        .x_dir    (arc_sd[0]),
        .y_step   (arc_ys),
        .y_dir    (arc_sd[1]),
        .z_step   (arc_zs),
        .z_dir    (arc_zd_nc),
        .last     (arc_last_nc),
        .err      (arc_errs_nc),
        .late     (arc_late_nc),
        .dir_valid(arc_dvalid),
        .nx_dir   (arc_nx),
        .ny_dir   (arc_ny)
    );
    end else begin : g_noarc
      assign arc_busy_nc = 1'b0;
      assign arc_ending  = 1'b0;
      assign arc_end_err = 1'b0;
      assign arc_xs      = 1'b0;
      assign arc_sd      = 2'd0;
      assign arc_ys      = 1'b0;
      assign arc_zs      = 1'b0;
      assign arc_zd_nc   = 1'b0;
      assign arc_last_nc = 1'b0;
      assign arc_errs_nc = 1'b0;
      assign arc_late_nc = 1'b0;
      assign arc_dvalid  = 1'b0;
      assign arc_nx      = 1'b0;
      assign arc_ny      = 1'b0;
      // the arc's load fields are not used without arcs
      wire unused_arc = &{1'b0, s_axis_arc};
    end
  endgenerate

  // The running arc's plane (taken on accept of an arc) as per-axis masks: the axis of the walk's
  // u, v and of the helix (none for plane 3, which the decoder refuses). Arc step requests per
  // axis (u, v, and the helix when the axis exists).
  reg [N_AXES-1:0] u_mask_reg, v_mask_reg, h_mask_reg;
  function [N_AXES-1:0] axis_bit;  // the mask of axis i (0 when the build has no axis i)
    input integer i;
    integer j;
    begin
      for (j = 0; j < N_AXES; j = j + 1) axis_bit[j] = (j == i);
    end
  endfunction
  wire [N_AXES-1:0] arc_uv = u_mask_reg | v_mask_reg;  // in-arc DIR writes and checks
  // the direction of the axis's arc step (u: x_dir, v: y_dir)
  wire [N_AXES-1:0] arc_sdir = (u_mask_reg & {N_AXES{arc_sd[0]}}) |
                               (~u_mask_reg & {N_AXES{arc_sd[1]}});
  assign arc_req = (u_mask_reg & {N_AXES{arc_xs}}) | (v_mask_reg & {N_AXES{arc_ys}}) |
                   (h_mask_reg & {N_AXES{arc_zs}});
  assign arc_ann = {N_AXES{arc_tick && arc_dvalid}} &
                   ((u_mask_reg & ({N_AXES{arc_nx}} ^ dir_tgt)) |
                    (v_mask_reg & ({N_AXES{arc_ny}} ^ dir_tgt)));
  reg arc_err_reg;

  dir_sequencer #(
      .N_AXES(N_AXES)
  ) u_dirseq (
      .clk          (clk),
      .rst          (rst),
      .abort        (abort),
      .accept       (accept),
      .seg_dir      (s_axis_dir),
      .moving       (moving),
      .in_hold      (state_reg == S_HOLD),
      .in_setup     (state_reg == S_SETUP),
      .arc_ann      (arc_ann),
      .arc_req      (arc_req),
      .arc_uv       (arc_uv),
      .arc_sdir     (arc_sdir),
      .pulse_hold_ok(pulse_hold_ok),
      .dir          (dir),
      .cfg_dir_setup(cfg_dir_setup),
      .dir_tgt      (dir_tgt),
      .rev          (rev),
      .pend         (pend),
      .dir_wr       (dir_wr),
      .hold_clear   (hold_clear),
      .setup_ok     (setup_ok),
      .settled      (settled),
      .arc_dir_viol (arc_dir_viol)
`ifdef FORMAL
      ,
      .f_setup_axes (f_setup_axes),
      .f_setup_cnt  (f_setup_cnt),
      .f_settle     (f_settle),
      .f_setup_max  (f_setup_max)
`endif
  );

  // one channel per axis: its DDAs, STEP / DIR pins and position (rtl/motion/axis_channel.v)
  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_axis
      axis_channel #(
          .PROFILES(PROFILES),
          .LEAN_DDA(LEAN_DDA)
      ) u_chan (
          .clk          (clk),
          .rst          (rst),
          .load         (accept),
          .prof_load    (accept && prof_in),
          .steps        (s_axis_steps[32*a+:32]),
          .tmn          (s_axis_tmn[64*a+:64]),
          .total        (s_axis_total),
          .prof_n_dom   (s_axis_prof_n_dom),
          .prof_v0      (s_axis_prof_v0[71*a+:71]),
          .prof_vc      (s_axis_prof_vc[71*a+:71]),
          .prof_vx      (s_axis_prof_vx[71*a+:71]),
          .prof_acc     (s_axis_prof_acc[56*a+:56]),
          .line_tick    (line_tick),
          .prof_tick    (prof_tick),
          .prof_op      (prof_op),
          .arc_req      (arc_req[a]),
          .abort        (abort),
          .step_block   (step_block[a]),
          .cfg_step_high(cfg_step_high[16*a+:16]),
          .cfg_step_low (cfg_step_low[16*a+:16]),
          .cfg_dir_hold (cfg_dir_hold[16*a+:16]),
          .dir_in       (dir_tgt[a]),
          .dir_wr       (dir_wr[a]),
          .moving       (moving[a]),
          .step_want    (step_want[a]),
          .step         (step[a]),
          .dir          (dir[a]),
          .idle         (pulse_idle[a]),
          .hold_ok      (pulse_hold_ok[a]),
          .violation    (pulse_violation[a]),
          .position     (position[32*a+:32])
      );
    end
  endgenerate

  always @(posedge clk) begin : seq
    seg_start_reg <= 1'b0;
    seg_done_reg  <= 1'b0;
    arc_err_reg   <= arc_tick && arc_ending && arc_end_err && !abort;
    // held until the tick that ends the arc (the first tick after the ending one)
    arc_end_reg   <= (arc_tick && arc_ending && !abort) || (arc_end_reg && !tick && !abort);

    // tick counter: loaded on accept, counts down during RUN
    if (accept) begin
      left_reg <= s_axis_total;
      last_reg <= (s_axis_total == 64'd1);
    end else if (tick) begin
      left_reg <= left_reg - 64'd1;
      last_reg <= (left_reg == 64'd2);
    end

    if (accept && arc_in) begin
      u_mask_reg <= (s_axis_arc_plane == 2'd0) ? axis_bit(0) : (s_axis_arc_plane == 2'd1) ?
                    axis_bit(2) : (s_axis_arc_plane == 2'd2) ? axis_bit(1) : {N_AXES{1'b0}};
      v_mask_reg <= (s_axis_arc_plane == 2'd0) ? axis_bit(1) : (s_axis_arc_plane == 2'd1) ?
                    axis_bit(0) : (s_axis_arc_plane == 2'd2) ? axis_bit(2) : {N_AXES{1'b0}};
      h_mask_reg <= (s_axis_arc_plane == 2'd0) ? axis_bit(2) : (s_axis_arc_plane == 2'd1) ?
                    axis_bit(1) : (s_axis_arc_plane == 2'd2) ? axis_bit(0) : {N_AXES{1'b0}};
    end
    if (accept) begin
      kind_reg  <= prof_in ? K_PROFILE : arc_in ? K_ARC : K_LINE;
      code_reg  <= s_axis_code;
      power_reg <= s_axis_power;
      v2_reg    <= s_axis_v2;
    end

    case (state_reg)
      S_IDLE: begin
        if (accept) begin
          if (zero_len) begin
            seg_done_reg    <= 1'b1;
            seg_done_v2_reg <= s_axis_v2;
          end else if ((rev | pend) != {N_AXES{1'b0}}) begin
            state_reg <= S_HOLD;
          end else begin
            state_reg     <= S_RUN;
            seg_start_reg <= 1'b1;
            laser_reg     <= cutting;
          end
        end
      end
      S_HOLD: begin
        if (hold_clear) state_reg <= S_SETUP;  // DIR written on this edge
      end
      S_SETUP: begin
        if (setup_ok) begin
          state_reg     <= S_RUN;
          seg_start_reg <= 1'b1;
          laser_reg     <= (code_reg != 2'd0) && (power_reg != 8'd0);
        end
      end
      S_RUN: begin
        if (run_last) begin
          seg_done_reg    <= 1'b1;
          seg_done_v2_reg <= v2_reg;
          if (!accept) begin
            state_reg <= S_IDLE;
            laser_reg <= 1'b0;
          end else if (zero_len) begin
            state_reg <= S_ZERO;
            laser_reg <= 1'b0;
          end else if (rev != {N_AXES{1'b0}} && !s_axis_dir_fast) begin
            state_reg <= S_HOLD;
            laser_reg <= 1'b0;
          end else begin
            seg_start_reg <= 1'b1;  // zero gap: R' = this edge
            laser_reg     <= cutting;
          end
        end
      end
      S_ZERO: begin
        seg_done_reg    <= 1'b1;
        seg_done_v2_reg <= v2_reg;
        state_reg       <= S_IDLE;
      end
      default: state_reg <= S_IDLE;
    endcase

    if (abort) begin
      state_reg     <= S_IDLE;
      laser_reg     <= 1'b0;
      seg_start_reg <= 1'b0;
      seg_done_reg  <= 1'b0;
    end

    if (rst) begin
      state_reg       <= S_IDLE;
      kind_reg        <= K_LINE;
      code_reg        <= 2'd0;
      power_reg       <= 8'd0;
      v2_reg          <= 1'b0;
      left_reg        <= 64'd0;
      last_reg        <= 1'b0;
      laser_reg       <= 1'b0;
      seg_start_reg   <= 1'b0;
      seg_done_reg    <= 1'b0;
      seg_done_v2_reg <= 1'b0;
      u_mask_reg      <= axis_bit(0);  // plane 0 (XY)
      v_mask_reg      <= axis_bit(1);
      h_mask_reg      <= axis_bit(2);
      arc_err_reg     <= 1'b0;
      arc_end_reg     <= 1'b0;
    end
  end

  // ---------------------------------------------------------------- machine outputs
  generate
    if (OUTPUTS != 0) begin : g_out
      reg [6:0] lvl_reg;  // {laser_dyn, dout[3:0], mist, flood}
      reg [7:0] duty_reg;
      reg [15:0] pend_n_reg;  // OUTPUT entries handed over and not applied yet (0: none)
      reg [7:0] pend_mask_reg;  // {laser_dyn, dout[3:0], fan, mist, flood}
      reg [7:0] pend_val_reg;  // the same bits (fan: 0)
      reg [7:0] pend_duty_reg;
      reg done_reg;
      reg [15:0] done_n_reg;
      wire take_out = s_out_tvalid && !abort && (pend_n_reg != 16'hFFFF);
      // the pending entry with the one handed over in this clock merged in (its bits win)
      wire [7:0] in_mask = s_out_tdata[23:16];
      wire [7:0] in_val = s_out_tdata[15:8];
      wire [7:0] m_mask = take_out ? (pend_mask_reg | in_mask) : pend_mask_reg;
      wire [7:0] m_val = take_out ? ((pend_val_reg & ~in_mask) | (in_val & in_mask)) : pend_val_reg;
      wire [7:0] m_duty = (take_out && in_mask[2]) ? s_out_tdata[7:0] : pend_duty_reg;
      wire [15:0] m_n = pend_n_reg + {15'd0, take_out};
      // the segment in progress (if any) ends on this edge
      wire ends_now = (state_reg == S_IDLE) || (state_reg == S_ZERO) || run_last;
      wire [6:0] lvl_mask = {m_mask[7:3], m_mask[1:0]};
      wire [6:0] lvl_val = {m_val[7:3], m_val[1:0]};
      always @(posedge clk) begin
        done_reg <= 1'b0;
        if (m_n != 16'd0 && ends_now) begin
          lvl_reg       <= (lvl_reg & ~lvl_mask) | (lvl_val & lvl_mask);
          if (m_mask[2]) duty_reg <= m_duty;
          done_reg      <= 1'b1;
          done_n_reg    <= m_n;
          pend_n_reg    <= 16'd0;
          pend_mask_reg <= 8'd0;
          pend_val_reg  <= 8'd0;
        end else begin
          pend_n_reg    <= m_n;
          pend_mask_reg <= m_mask;
          pend_val_reg  <= m_val;
        end
        pend_duty_reg <= m_duty;
        if (abort || rst) begin
          lvl_reg[5:0]  <= 6'd0;  // laser_dyn is a mode, not an output: kept (cleared by rst)
          duty_reg      <= 8'd0;
          pend_n_reg    <= 16'd0;
          pend_mask_reg <= 8'd0;
          pend_val_reg  <= 8'd0;
          pend_duty_reg <= 8'd0;
          done_reg      <= 1'b0;
        end
        if (rst) begin
          done_n_reg <= 16'd0;
          lvl_reg[6] <= 1'b0;
        end
      end
      assign s_out_tready  = !abort && (pend_n_reg != 16'hFFFF);
      assign coolant_flood = lvl_reg[0];
      assign coolant_mist  = lvl_reg[1];
      assign dout          = lvl_reg[5:2];
      assign laser_dyn     = lvl_reg[6];
      assign fan_duty      = duty_reg;
      assign out_done      = done_reg;
      assign out_done_n    = done_n_reg;
    end else begin : g_noout
      assign s_out_tready  = 1'b0;
      assign coolant_flood = 1'b0;
      assign coolant_mist  = 1'b0;
      assign dout          = 4'd0;
      assign fan_duty      = 8'd0;
      assign laser_dyn     = 1'b0;
      assign out_done      = 1'b0;
      assign out_done_n    = 16'd0;
      wire unused_out = &{1'b0, s_out_tvalid, s_out_tdata};
    end
  endgenerate

  assign s_axis_tready = ready;
  assign laser         = laser_reg && !abort;
  assign busy          = (state_reg != S_IDLE);
  assign idle          = (state_reg == S_IDLE) && (&pulse_idle);
  assign running       = (state_reg == S_RUN);
  assign rapid_seg     = (code_reg == 2'd0);
  assign power         = power_reg;
  assign prof_run      = (kind_reg == K_PROFILE);
  assign seg_start     = seg_start_reg;
  assign seg_done      = seg_done_reg;
  assign seg_done_v2   = seg_done_v2_reg;
  assign violation     = (|pulse_violation) || arc_dir_viol;
  assign arc_err       = arc_err_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh, k-induction). Assumes only reset in the first clock.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  always @(*)
    if (f_past_valid) begin
      // Laser is low while the executor is idle (or waiting for DIR hold/setup, or completing a
      // zero-length segment), during a rapid (code 0) segment and at power 0: it can only be high
      // while RUN executes a segment of code 1..3 with power > 0.
      if (state_reg != S_RUN) assert (!laser);
      if (code_reg == 2'd0) assert (!laser);
      if (power_reg == 8'd0) assert (!laser);
      // E-stop (abort): the laser is low in the abort clock itself.
      if (abort) assert (!laser);
    end

`ifdef FORMAL_DIR
  // DIR timing at the pins (scripts/formal/executor_dir.ys): no STEP rising edge within DIR setup
  // clocks after a DIR change, and no DIR change within DIR hold clocks after a STEP rising edge.
  // Proved for segments taken through HOLD/SETUP (s_axis_dir_fast = 0 assumed; inputs as
  // segment_prep makes them, below): the zero-gap
  // reversal path relies on segment_prep's arithmetic (floor(T/n_dom) >= hold + setup), which the
  // benches check edge for edge against the reference model. Configuration assumed stable.
  reg [64*N_AXES-1:0] f_cfg_q;
  always @(posedge clk) f_cfg_q <= {cfg_step_high, cfg_step_low, cfg_dir_setup, cfg_dir_hold};
  always @(*) if (f_past_valid) assume ({cfg_step_high, cfg_step_low, cfg_dir_setup, cfg_dir_hold} == f_cfg_q);
  always @(*) assume (!s_axis_dir_fast);
  // ARC segments reverse X/Y inside the arc (at the quadrant points); there a step too close to its
  // DIR change is reported as a timing violation, not delayed (docs/motion.md, Arcs): not covered.
  always @(*) if (s_axis_tvalid) assume (s_axis_kind != K_ARC);
  always @(*) if (f_past_valid && !rst) assert (kind_reg != K_ARC);  // induction invariant
  // No STEP timing violation (a step requested before the previous pulse's high + low time; the
  // prep's clamp T >= n_dom * min_period prevents it, a violation is counted and latched as a
  // fault): step_pulse assumes it never holds a pending step under FORMAL_DIR.
  reg [N_AXES-1:0] f_step_q, f_dir_q;
  reg f_rst_q;  // the pins' values before a reset edge do not count as changes
  reg f_abort_q;  // abort was high in the previous clock
  reg [N_AXES-1:0] f_block_q;  // step_block in the previous clock
  wire [N_AXES-1:0] f_dir_chg = f_rst_q ? {N_AXES{1'b0}} : (dir ^ f_dir_q);
  wire [N_AXES-1:0] f_step_rise = f_rst_q ? {N_AXES{1'b0}} : (step & ~f_step_q);
  reg [17*N_AXES-1:0] f_since_dir, f_since_step;  // clocks since the pin changed, saturating
  integer f_a;
  always @(posedge clk) begin
    f_step_q <= step;
    f_dir_q  <= dir;
    f_rst_q  <= rst;
    f_abort_q <= abort;
    f_block_q <= step_block;
    for (f_a = 0; f_a < N_AXES; f_a = f_a + 1) begin
      if (f_dir_chg[f_a]) f_since_dir[17*f_a+:17] <= 17'd1;
      else if (f_since_dir[17*f_a+:17] != 17'h10000)
        f_since_dir[17*f_a+:17] <= f_since_dir[17*f_a+:17] + 17'd1;
      if (f_step_rise[f_a]) f_since_step[17*f_a+:17] <= 17'd1;
      else if (f_since_step[17*f_a+:17] != 17'h10000)
        f_since_step[17*f_a+:17] <= f_since_step[17*f_a+:17] + 17'd1;
    end
    if (rst) begin
      f_since_dir  <= {N_AXES{17'h10000}};
      f_since_step <= {N_AXES{17'h10000}};
    end
  end
  genvar f_g;
  generate
    for (f_g = 0; f_g < N_AXES; f_g = f_g + 1) begin : g_f_dir
      // Clocks since this axis's DIR edge (0 in the clock right after the edge that changed it).
      wire [16:0] f_sd = f_dir_chg[f_g] ? 17'd0 : f_since_dir[17*f_g+:17];
      wire [16:0] f_setup = (cfg_dir_setup[16*f_g+:16] == 16'd0) ? 17'd1 : {1'b0, cfg_dir_setup[16*f_g+:16]};
      // segment_prep's output contract: n <= T, tmn = T - n.
      always @(*)
        if (s_axis_tvalid)
          assume ({32'd0, s_axis_steps[32*f_g+:32]} <= s_axis_total &&
                  s_axis_tmn[64*f_g+:64] == s_axis_total - {32'd0, s_axis_steps[32*f_g+:32]});
      always @(*)
        if (f_past_valid && !rst) begin
          // A STEP rising edge now: the last DIR change was at least DIR setup clocks ago.
          if (f_step_rise[f_g]) assert (f_sd >= f_setup);
          // E-stop (abort): no STEP rising edge on the clock after an abort clock (held abort:
          // none at all; a pulse already high finishes its high time).
          if (f_abort_q) assert (!f_step_rise[f_g]);
          // Hard limits: no STEP rising edge of an axis on the clock after it was blocked.
          if (f_block_q[f_g]) assert (!f_step_rise[f_g]);
          // DIR hold, compositionally: the executor writes DIR only when step_pulse's hold_ok is
          // high, and step_pulse (set step_pulse) proves that DIR changes only on a write and that
          // hold_ok means at least DIR hold clocks since the last STEP rising edge.
          if (dir_wr[f_g]) assert (pulse_hold_ok[f_g]);
          // Induction invariants: DIR writes happen only on leaving HOLD; in SETUP the written axes
          // changed DIR exactly f_setup_cnt - 1 clocks ago, every other axis (and every axis in
          // any other state) at least DIR setup clocks ago.
          if (state_reg != S_HOLD) assert (!pend[f_g]);
          assert (f_since_dir[17*f_g+:17] <= 17'h10000);
          assert ((dir[f_g] != dir_tgt[f_g]) == pend[f_g]);
          if (state_reg == S_SETUP && f_setup_axes[f_g])
            assert (f_sd + 17'd1 == {1'b0, f_setup_cnt} && f_setup_cnt != 16'd0);
          else assert (f_sd + {1'b0, f_settle} >= f_setup);
          if (state_reg != S_IDLE) assert (f_settle == 16'd0);
          if (f_past_valid && !f_rst_q) assert (f_setup_max >= f_setup);
        end
    end
  endgenerate
`endif
`endif

endmodule

`default_nettype wire
