// dir_sequencer: segment_executor's DIR bookkeeping: which DIR level each axis must have, when a
// DIR pin may be written (DIR hold) and when a step may follow the write (DIR setup)
// (docs/timing.md "Queued segments"; the executor's header states the schedule).
//
// dir_tgt: per axis the DIR level written or pending (the pins' level after reset: 0). On the
// executor's accept edge (accept) the moving axes take the segment's directions (seg_dir); in
// any other clock an arc's announced reversal (arc_ann) flips the axis. rev: the moving axes of
// the segment at the executor's input whose direction differs from dir_tgt.
// pend: a DIR write pending per axis: set on accept for the reversing axes (rev), or by arc_ann;
// cleared by the write. dir_wr (to the axis's step_pulse, which changes the pin on that edge): in
// HOLD (in_hold) every pending axis together once each has its DIR hold (hold_clear); in any
// other state each pending axis as soon as its own hold has elapsed (hold_ok: step_pulse's hold_ok
// and no arc step request of the axis in this clock). No write in an abort clock.
// SETUP: on leaving HOLD (in_hold && hold_clear) the written axes are recorded and a counter
// starts at 1 in the first SETUP clock; setup_ok is high when it has reached the DIR setup of
// every written axis (the executor then runs from the next edge: D + max(largest setup, 1)).
// abort: the pending writes are cancelled (dir_tgt takes the pins' level) and settled is low until
// the largest DIR setup setting of all axes (registered, at least 1) has passed: a DIR edge just
// before the abort still gets its setup time before a segment is accepted from idle.
// In-arc check (axes 0..2, those an arc's u / v can be on): a step request of an arc's u / v axis
// (arc_req && arc_uv) whose direction (arc_sdir) is not on the DIR pin yet, or that comes less than
// DIR setup after the axis's last DIR write, strobes arc_dir_viol one clock later (reported, not
// delayed).
`default_nettype none

module dir_sequencer #(
    parameter N_AXES = 4  // 2..
) (
    input wire clk,
    input wire rst,
    /* verilator lint_off SYMRSVDWORD */
    input wire abort,  // e-stop
    /* verilator lint_on SYMRSVDWORD */

    input wire              accept,   // the executor accepts a segment on this edge
    input wire [N_AXES-1:0] seg_dir,  // its directions (1 = positive)
    input wire [N_AXES-1:0] moving,   // its moving axes
    input wire              in_hold,  // the executor is in HOLD
    input wire              in_setup, // the executor is in SETUP

    input wire [N_AXES-1:0] arc_ann,   // ARC: the next u / v move reverses the axis
    input wire [N_AXES-1:0] arc_req,   // ARC: the walk's step requests
    input wire [N_AXES-1:0] arc_uv,    // ARC: the axes of the walk's u and v
    input wire [N_AXES-1:0] arc_sdir,  // ARC: the direction of the axis's arc step

    input wire [N_AXES-1:0] pulse_hold_ok,  // per axis step_pulse's hold_ok
    input wire [N_AXES-1:0] dir,            // the DIR pins

    input wire [16*N_AXES-1:0] cfg_dir_setup,

    output wire [N_AXES-1:0] dir_tgt,
    output wire [N_AXES-1:0] rev,
    output wire [N_AXES-1:0] pend,
    output wire [N_AXES-1:0] dir_wr,
    output wire              hold_clear,   // every pending axis has its DIR hold
    output wire              setup_ok,     // SETUP: every written axis has had its DIR setup (x outside SETUP)
    output wire              settled,      // no post-abort wait
    output wire              arc_dir_viol  // 1-clock strobe (see above)
`ifdef FORMAL
    ,  // the registers the executor's induction invariants name (rtl/motion/segment_executor.v)
    output wire [N_AXES-1:0] f_setup_axes,
    output wire [      15:0] f_setup_cnt,
    output wire [      15:0] f_settle,
    output wire [      15:0] f_setup_max
`endif
);

  generate
    if (N_AXES < 2) begin : g_bad_n_axes
      dir_sequencer_illegal_N_AXES_below_2 u_err ();
    end
  endgenerate

  reg [N_AXES-1:0] dir_tgt_reg;  // DIR level written or pending per axis
  reg [N_AXES-1:0] pend_reg;  // DIR write pending
  reg [15:0] setup_cnt_reg;
  reg [N_AXES-1:0] setup_axes_reg;  // axes whose DIR was written on leaving HOLD
  reg [15:0] settle_reg;  // after an abort: clocks before a segment is accepted from IDLE again
  reg [15:0] setup_max_reg;  // the largest DIR setup setting of all axes (registered)

  // The largest setting, one compare deep: every pair of axes compared in parallel, the axis that
  // is >= every lower-numbered axis and > every higher-numbered one wins (exactly one), an AND-OR
  // selects it (a compare chain over the axes was the iCE40 critical path).
  reg [15:0] setup_max_w;
  reg [N_AXES-1:0] sm_win;
  reg sm_zero;
  integer sm_i, sm_j;
  always @(*) begin
    sm_win = {N_AXES{1'b1}};
    sm_zero = 1'b1;
    for (sm_i = 0; sm_i < N_AXES; sm_i = sm_i + 1) begin
      for (sm_j = 0; sm_j < N_AXES; sm_j = sm_j + 1) begin
        if (sm_j < sm_i && !(cfg_dir_setup[16*sm_i+:16] > cfg_dir_setup[16*sm_j+:16]))
          sm_win[sm_i] = 1'b0;
        if (sm_j > sm_i && !(cfg_dir_setup[16*sm_i+:16] >= cfg_dir_setup[16*sm_j+:16]))
          sm_win[sm_i] = 1'b0;
      end
      if (cfg_dir_setup[16*sm_i+:16] != 16'd0) sm_zero = 1'b0;
    end
    setup_max_w = 16'd0;
    for (sm_i = 0; sm_i < N_AXES; sm_i = sm_i + 1)
      setup_max_w = setup_max_w | (cfg_dir_setup[16*sm_i+:16] & {16{sm_win[sm_i]}});
  end
  always @(posedge clk) setup_max_reg <= sm_zero ? 16'd1 : setup_max_w;

  // an arc step request (registered in arc_dda, not yet seen by step_pulse's hold_ok) counts as a
  // STEP rise: no DIR write of that axis in its clock (an in-arc reversal at a quadrant point)
  wire [N_AXES-1:0] hold_ok = pulse_hold_ok & ~arc_req;
  assign hold_clear = ((pend_reg & ~hold_ok) == {N_AXES{1'b0}});
  assign dir_wr = {N_AXES{!abort}} & (in_hold ? (pend_reg & {N_AXES{hold_clear}})
                                              : (pend_reg & hold_ok));
  assign rev = (seg_dir ^ dir_tgt_reg) & moving;

  // SETUP ends when the clocks since the DIR write (setup_cnt_reg, 1 in the first SETUP clock)
  // reach the DIR setup of every axis written on leaving HOLD: one compare per axis in parallel.
  // Formed only in SETUP (x otherwise: the executor reads setup_ok only there), so a simulator
  // skips it in every other clock (docs/architecture.md "Simulation speed").
  reg setup_ok_w;
  integer sk;
  always @(*) begin
    setup_ok_w = 1'bx;
    if (in_setup) begin
      setup_ok_w = 1'b1;
      for (sk = 0; sk < N_AXES; sk = sk + 1)
        if (setup_axes_reg[sk] && setup_cnt_reg < cfg_dir_setup[16*sk+:16]) setup_ok_w = 1'b0;
    end
  end
  assign setup_ok = setup_ok_w;

  localparam integer NSW = (N_AXES >= 3) ? 3 : 2;  // axes an arc's u / v can be on
  reg [16*NSW-1:0] since_wr_reg;  // clocks since the last DIR write per axis (saturating)
  reg arc_dir_viol_reg;

  integer k;
  always @(posedge clk) begin
    pend_reg <= (pend_reg & ~dir_wr) | (accept ? rev : arc_ann);
    if (accept) dir_tgt_reg <= (dir_tgt_reg & ~moving) | (seg_dir & moving);
    else dir_tgt_reg <= dir_tgt_reg ^ arc_ann;
    arc_dir_viol_reg <= 1'b0;
    for (k = 0; k < NSW; k = k + 1) begin
      if (dir_wr[k]) since_wr_reg[16*k+:16] <= 16'd1;
      else if (since_wr_reg[16*k+:16] != 16'hFFFF)
        since_wr_reg[16*k+:16] <= since_wr_reg[16*k+:16] + 16'd1;
      if (arc_req[k] && arc_uv[k] && !abort &&
          (arc_sdir[k] != dir[k] || since_wr_reg[16*k+:16] < cfg_dir_setup[16*k+:16]))
        arc_dir_viol_reg <= 1'b1;
    end
    if (in_hold && hold_clear) begin
      setup_cnt_reg  <= 16'd1;
      setup_axes_reg <= pend_reg;
    end
    if (in_setup && !setup_ok) setup_cnt_reg <= setup_cnt_reg + 16'd1;
    if (settle_reg != 16'd0) settle_reg <= settle_reg - 16'd1;
    if (abort) begin
      settle_reg  <= setup_max_reg;
      pend_reg    <= {N_AXES{1'b0}};  // pending DIR writes are cancelled: DIR keeps its level
      dir_tgt_reg <= dir;
    end
    if (rst) begin
      dir_tgt_reg      <= {N_AXES{1'b0}};
      pend_reg         <= {N_AXES{1'b0}};
      setup_cnt_reg    <= 16'd0;
      setup_axes_reg   <= {N_AXES{1'b0}};
      settle_reg       <= 16'd0;
      since_wr_reg     <= {NSW{16'hFFFF}};
      arc_dir_viol_reg <= 1'b0;
    end
  end

  assign dir_tgt      = dir_tgt_reg;
  assign pend         = pend_reg;
  assign settled      = (settle_reg == 16'd0);
  assign arc_dir_viol = arc_dir_viol_reg;
`ifdef FORMAL
  assign f_setup_axes = setup_axes_reg;
  assign f_setup_cnt  = setup_cnt_reg;
  assign f_settle     = settle_reg;
  assign f_setup_max  = setup_max_reg;
`endif

endmodule

`default_nettype wire
