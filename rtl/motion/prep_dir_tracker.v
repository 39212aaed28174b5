// prep_dir_tracker: segment_prep's DIR tracking and its dir_fast decision (docs/timing.md "Queued
// segments"): per axis the DIR level the executor will have when the segment being prepared
// starts, and whether that segment may run with no gap although an axis reverses.
//
// track: after reset 0 (DIR low). A prepared non-arc segment (sub, its last preparation clock)
// sets the moving axes to its directions (dir); an arc (afix) sets the axes of fix_trk to
// fix_dir (segment_prep's prep_arc: the arc's start directions).
// dir_fast (registered with the prepared segment): 1 iff every moving axis that reverses (dir !=
// track) has P >= max(DIR hold, 1) + max(DIR setup, 1), the segment is not a PROFILE one (prof),
// and no moving axis is "unknown". The check runs during segment_prep's multiplier: mul_start
// (its iteration 0) takes the reversing axes; in each following clock (mul_step) axis scan_idx's
// hold' + setup' is registered and compared with P (period) one clock later (two stages; scan_idx
// is segment_prep's axis index, 0 at mul_start, counting up to N_AXES - 1 and staying there).
// unknown axes: the arc's u / v (fix_unk: their DIR at the arc's end is not known) until they move
// in a prepared non-arc segment; every axis after an abort (e-stop drops segments whose DIR was
// already tracked). An arc is prepared with dir_fast 0.
`default_nettype none

module prep_dir_tracker #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,
    /* verilator lint_off SYMRSVDWORD */
    input wire abort,
    /* verilator lint_on SYMRSVDWORD */

    input wire              mul_start,  // segment_prep's multiplier, iteration 0
    input wire              mul_step,   // ... iterations 1..32
    input wire              sub,        // the last clock of a non-arc segment's preparation
    input wire              afix,       // the last clock of an arc's preparation
    input wire [N_AXES-1:0] dir,        // the segment's directions
    input wire [N_AXES-1:0] moving,     // its moving axes
    input wire              prof,       // it is a PROFILE segment
    input wire [      31:0] period,     // P
    input wire [(N_AXES > 1 ? $clog2(N_AXES) : 1)-1:0] scan_idx,

    input wire [N_AXES-1:0] fix_dir,  // AFIX: the arc's start directions
    input wire [N_AXES-1:0] fix_trk,  // AFIX: the axes that take them
    input wire [N_AXES-1:0] fix_unk,  // AFIX: the axes whose DIR becomes unknown

    input wire [16*N_AXES-1:0] cfg_dir_setup,
    input wire [16*N_AXES-1:0] cfg_dir_hold,

    output wire dir_fast
);

  generate
    if (N_AXES < 1) begin : g_bad_n_axes
      prep_dir_tracker_illegal_N_AXES_below_1 u_err ();
    end
  endgenerate

  reg [N_AXES-1:0] dir_track_reg;  // DIR when the segment being prepared starts
  reg [N_AXES-1:0] rev_reg;  // moving axes that reverse
  reg fast_reg;  // no reversing axis checked so far has P < hold' + setup'
  reg chk_rev_reg;  // the axis in chk_hs_reg reverses
  reg [16:0] chk_hs_reg;  // max(hold,1) + max(setup,1) of one axis
  reg dir_fast_reg;
  reg [N_AXES-1:0] unk_reg;  // axes whose DIR is not known (after an arc, after an abort)

  // hold' + setup' of axis scan_idx into chk_hs_reg, then the compare with P
  wire [15:0] chk_hold = cfg_dir_hold[16*scan_idx+:16];
  wire [15:0] chk_setup = cfg_dir_setup[16*scan_idx+:16];
  wire [16:0] chk_hs = {1'b0, (chk_hold == 16'd0) ? 16'd1 : chk_hold} +
                       {1'b0, (chk_setup == 16'd0) ? 16'd1 : chk_setup};

  always @(posedge clk) begin
    if (mul_start) begin
      rev_reg     <= (dir ^ dir_track_reg) & moving;
      fast_reg    <= 1'b1;
      chk_rev_reg <= 1'b0;
    end
    if (mul_step) begin
      // axis k: sum in iteration k + 1, compare in k + 2 (the last axis repeats harmlessly)
      chk_hs_reg  <= chk_hs;
      chk_rev_reg <= rev_reg[scan_idx];
      if (chk_rev_reg && period < {15'd0, chk_hs_reg}) fast_reg <= 1'b0;
    end
    if (sub) begin
      dir_fast_reg  <= fast_reg && !prof && ((moving & unk_reg) == {N_AXES{1'b0}});
      unk_reg       <= unk_reg & ~moving;
      dir_track_reg <= (dir_track_reg & ~moving) | (dir & moving);
    end
    if (afix) begin
      dir_fast_reg  <= 1'b0;
      unk_reg       <= unk_reg | fix_unk;
      dir_track_reg <= (dir_track_reg & ~fix_trk) | (fix_dir & fix_trk);
    end
    if (abort) unk_reg <= {N_AXES{1'b1}};
    if (rst) begin
      dir_track_reg <= {N_AXES{1'b0}};
      rev_reg       <= {N_AXES{1'b0}};
      fast_reg      <= 1'b0;
      chk_rev_reg   <= 1'b0;
      chk_hs_reg    <= 17'd0;
      dir_fast_reg  <= 1'b0;
      unk_reg       <= {N_AXES{1'b0}};
    end
  end

  assign dir_fast = dir_fast_reg;

endmodule

`default_nettype wire
