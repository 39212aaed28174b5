// axis_channel: one axis of segment_executor: its step generators, its STEP / DIR pins and its
// position (docs/timing.md "Queued segments", "Profiled segments").
//
// Step generators: dda_linear (kind LINE, advances on line_tick) and, with PROFILES != 0,
// dda_profile (kind PROFILE, advances on prof_tick with profile_gen's op); both are loaded on the
// executor's accept edge (load; prof_load for a PROFILE segment). arc_req is the arc walk's step
// request for this axis (the executor routes arc_dda's u / v / helix steps by plane).
// step_want = the OR of the three requests; the request issued to step_pulse is step_want in a
// clock without abort and without step_block (hard limits): no STEP rises on the next edge and the
// position does not change.
// step_pulse shapes STEP (high / low times) and owns the DIR pin: DIR takes dir_in on a clock with
// dir_wr (the executor's DIR sequencer writes only when hold_ok, DIR hold elapsed since the last
// STEP rise); idle, hold_ok and violation are step_pulse's (rtl/motion/step_pulse.v).
// position: signed step count, +1 / -1 by the DIR pin on the edge STEP rises; 0 after reset.
// moving: the segment at the executor's input moves this axis (|steps| != 0).
// Build options (segment_executor passes them): PROFILES = 0 leaves dda_profile out (prof_* are not
// used); LEAN_DDA = 1 builds dda_linear computing T - n from total (tmn not used) with no
// steps-left counter.
`default_nettype none

module axis_channel #(
    parameter PROFILES = 1,  // 0: no dda_profile
    parameter LEAN_DDA = 0   // 1: dda_linear takes T - n from total, no steps-left counter
) (
    input wire clk,
    input wire rst,

    input wire        load,       // the executor accepts a segment on this edge
    input wire        prof_load,  // ... and it is a PROFILE segment
    input wire [31:0] steps,      // |steps| of the segment at the executor's input
    input wire [63:0] tmn,        // T - |steps|
    input wire [63:0] total,      // T

    input wire [23:0] prof_n_dom,
    input wire [70:0] prof_v0,  // V_entry * n
    input wire [70:0] prof_vc,  // V_cruise * n
    input wire [70:0] prof_vx,  // V_exit * n
    input wire [55:0] prof_acc, // A * n

    input wire       line_tick,  // a LINE tick (RUN of a LINE segment)
    input wire       prof_tick,  // a PROFILE tick
    input wire [1:0] prof_op,    // profile_gen's op of this tick
    input wire       arc_req,    // the arc walk's step request for this axis

    /* verilator lint_off SYMRSVDWORD */
    input wire abort,       // e-stop: no step request in this clock
    /* verilator lint_on SYMRSVDWORD */
    input wire step_block,  // hard limit: no step request in this clock

    input wire [15:0] cfg_step_high,
    input wire [15:0] cfg_step_low,
    input wire [15:0] cfg_dir_hold,

    input wire dir_in,  // the DIR level to write
    input wire dir_wr,  // write it (only when hold_ok)

    output wire        moving,     // steps != 0
    output wire        step_want,  // step request before abort and step_block
    output wire        step,
    output wire        dir,
    output wire        idle,       // step_pulse: STEP low and low time elapsed, nothing pending
    output wire        hold_ok,    // step_pulse: DIR hold elapsed since the last STEP rise
    output wire        violation,  // step_pulse: 1-clock strobe, a step before STEP low time
    output wire [31:0] position
);

  generate
    if (PROFILES != 0 && PROFILES != 1) begin : g_bad_profiles
      axis_channel_illegal_PROFILES_not_0_or_1 u_err ();
    end
    if (LEAN_DDA != 0 && LEAN_DDA != 1) begin : g_bad_lean_dda
      axis_channel_illegal_LEAN_DDA_not_0_or_1 u_err ();
    end
  endgenerate

  wire dda_step, prof_step;
  wire step_req = step_want && !abort && !step_block;
  reg [31:0] pos_reg;

  assign moving    = (steps != 32'd0);
  assign step_want = dda_step || prof_step || arc_req;

  dda_linear #(
      .TMN_FROM_TOTAL(LEAN_DDA),
      .STEP_GUARD    ((LEAN_DDA != 0) ? 0 : 1)
  ) u_dda (
      .clk  (clk),
      .rst  (rst),
      .load (load),
      .steps(steps),
      .tmn  (tmn),
      .total(total),
      .tick (line_tick),
      .step (dda_step)
  );

  generate
    if (PROFILES != 0) begin : g_pdda
      dda_profile u_pdda (
          .clk  (clk),
          .rst  (rst),
          .load (prof_load),
          .n_dom(prof_n_dom),
          .v0   (prof_v0),
          .vc   (prof_vc),
          .vx   (prof_vx),
          .acc  (prof_acc),
          .tick (prof_tick),
          .op   (prof_op),
          .step (prof_step)
      );
    end else begin : g_nopdda
      assign prof_step = 1'b0;
      // the profile fields are not used without profiles
      wire unused_prof = &{1'b0, prof_load, prof_n_dom, prof_v0, prof_vc, prof_vx, prof_acc,
                           prof_tick, prof_op};
    end
  endgenerate

  step_pulse u_pulse (
      .clk      (clk),
      .rst      (rst),
      .cfg_high (cfg_step_high),
      .cfg_low  (cfg_step_low),
      .cfg_hold (cfg_dir_hold),
      .step_req (step_req),
      .dir_in   (dir_in),
      .dir_wr   (dir_wr),
      .step     (step),
      .dir      (dir),
      .idle     (idle),
      .hold_ok  (hold_ok),
      .violation(violation)
  );

  always @(posedge clk) begin
    if (step_req) pos_reg <= dir ? pos_reg + 32'd1 : pos_reg - 32'd1;
    if (rst) pos_reg <= 32'd0;
  end
  assign position = pos_reg;

endmodule

`default_nettype wire
