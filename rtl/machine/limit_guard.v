// limit_guard: hard limits of N_AXES axes (docs/machine.md "Hard limits"): from the filtered limit
// switches, each axis's step request and DIR level and the executor's busy, the per-axis step
// block, the latched trip (the alarm), the switch that tripped and the position-not-trusted flag.
//
// Contract
//   lim_min[a], lim_max[a]   filtered switch levels (input_filter q, 1 = asserted, 0 for an
//                            absent switch), registers.
//   rise_min[a], rise_max[a] 1-clock strobes: the filtered level rose in this clock.
//   step_want[a]   axis a's step request before any gate (segment_executor step_want): a STEP
//                  rises on the next edge unless blocked or aborted.
//   dir[a]         DIR level of axis a (1 = positive: toward its max switch); the executor writes
//                  DIR at least one clock before a step request in that direction, so DIR in the
//                  request's clock is the direction of that step.
//   busy           the executor holds a segment (running, or waiting DIR hold / setup).
//   clear          FAULT_CLEAR (1-clock strobe).
//   sup_min[a], sup_max[a]   the switch's trips are suppressed in this clock (a HOME armed on it:
//                  rtl/machine/trigger_latch.v): neither its rise nor a step request toward it
//                  trips; its block stays.
//   trust          SET_POSITION (1-clock strobe): the positions are trusted again.
//   block[a]       1: no step request of axis a may be issued in this clock (its step would go
//                  toward an asserted switch, or the alarm is latched). From registers only.
//   trip           the alarm, latched: set on the edge after a clock in which an enabled switch
//                  rose while busy, or a step request went toward an asserted switch (switches
//                  not suppressed); cleared
//                  on the edge after a clear while the switch that tripped is released (a
//                  clear while it is held does nothing). cnc_core aborts motion while it is high.
//   trip_axis, trip_max   the switch that tripped (the lowest axis, min before max, when several
//                  trip in the same clock); kept after the clear until the next trip.
//   untrusted      set with trip; cleared by rst, and by trust while the alarm is not latched
//                  (and no trip on that edge).
// Stop bound: a switch whose filtered level rises in clock c blocks its axis's steps toward it
// in clock c itself (no STEP rise toward it from edge c + 1); other axes may still issue a step
// request in c (STEP rising on edge c + 1), none from clock c + 1 (trip, hence abort, is high).
`default_nettype none

module limit_guard #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire [N_AXES-1:0] lim_min,
    input wire [N_AXES-1:0] lim_max,
    input wire [N_AXES-1:0] rise_min,
    input wire [N_AXES-1:0] rise_max,
    input wire [N_AXES-1:0] step_want,
    input wire [N_AXES-1:0] dir,
    input wire              busy,
    input wire              clear,
    input wire [N_AXES-1:0] sup_min,
    input wire [N_AXES-1:0] sup_max,
    input wire              trust,

    output wire [N_AXES-1:0] block,
    output wire              trip,
    output wire [       3:0] trip_axis,
    output wire              trip_max,
    output wire              untrusted
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      limit_guard_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  reg trip_reg, untrusted_reg, trip_max_reg;
  reg [3:0] trip_axis_reg;

  wire [N_AXES-1:0] toward = (dir & lim_max) | (~dir & lim_min);  // a step now would go into a switch
  wire [N_AXES-1:0] cause_min = (({N_AXES{busy}} & rise_min) | (step_want & ~dir & lim_min)) &
                                ~sup_min;
  wire [N_AXES-1:0] cause_max = (({N_AXES{busy}} & rise_max) | (step_want & dir & lim_max)) &
                                ~sup_max;
  wire trip_now = |{cause_min, cause_max};

  // the first cause, axis 0 first, min before max
  reg [3:0] id_axis;
  reg id_max, id_found;
  integer i;
  always @(*) begin
    id_axis  = 4'd0;
    id_max   = 1'b0;
    id_found = 1'b0;
    for (i = 0; i < N_AXES; i = i + 1)
      if (!id_found && (cause_min[i] || cause_max[i])) begin
        id_axis  = i[3:0];
        id_max   = !cause_min[i];
        id_found = 1'b1;
      end
  end

  // the switch that tripped, now
  wire [15:0] min16 = {{(16 - N_AXES) {1'b0}}, lim_min};
  wire [15:0] max16 = {{(16 - N_AXES) {1'b0}}, lim_max};
  wire held = trip_max_reg ? max16[trip_axis_reg] : min16[trip_axis_reg];

  wire stays = trip_reg && !(clear && !held);  // latched, and not cleared in this clock

  always @(posedge clk) begin
    trip_reg <= trip_now || stays;
    if (trip_now) untrusted_reg <= 1'b1;
    else if (trust && !trip_reg) untrusted_reg <= 1'b0;
    if (trip_now && !stays) begin
      trip_axis_reg <= id_axis;
      trip_max_reg  <= id_max;
    end
    if (rst) begin
      trip_reg      <= 1'b0;
      untrusted_reg <= 1'b0;
      trip_axis_reg <= 4'd0;
      trip_max_reg  <= 1'b0;
    end
  end

  assign block     = toward | {N_AXES{trip_reg}};
  assign trip      = trip_reg;
  assign trip_axis = trip_axis_reg;
  assign trip_max  = trip_max_reg;
  assign untrusted = untrusted_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set limit_guard, k-induction; covers). Reset in the
  // first clock; every input free except that a rise strobe comes exactly when the level goes
  // from low to high (input_filter). `issued` is what passes the block (the executor's step_req
  // is step_want && !block && !abort; cnc_core's abort includes trip).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(*) begin
    assume ((rise_min & ~lim_min) == {N_AXES{1'b0}});
    assume ((rise_max & ~lim_max) == {N_AXES{1'b0}});
  end
  always @(posedge clk)
    if (f_past_valid) begin
      assume ((rise_min & $past(lim_min)) == {N_AXES{1'b0}});
      assume ((rise_max & $past(lim_max)) == {N_AXES{1'b0}});
      assume (((lim_min & ~$past(lim_min)) & ~rise_min) == {N_AXES{1'b0}});
      assume (((lim_max & ~$past(lim_max)) & ~rise_max) == {N_AXES{1'b0}});
    end

  reg [15:0] f_cmin_q, f_cmax_q;  // the causes of the previous clock
  reg [15:0] f_smin_q, f_smax_q;  // the suppressed switches of the previous clock
  always @(posedge clk) begin
    f_smin_q <= {{(16 - N_AXES) {1'b0}}, sup_min};
    f_smax_q <= {{(16 - N_AXES) {1'b0}}, sup_max};
    f_cmin_q <= {{(16 - N_AXES) {1'b0}}, cause_min};
    f_cmax_q <= {{(16 - N_AXES) {1'b0}}, cause_max};
  end

  wire [N_AXES-1:0] issued = step_want & ~block;

  always @(*)
    if (f_past_valid && !rst) begin
      // No step toward an asserted switch: a step issued goes away from it.
      assert ((issued & dir & lim_max) == {N_AXES{1'b0}});
      assert ((issued & ~dir & lim_min) == {N_AXES{1'b0}});
      // While the alarm is latched no step is issued.
      if (trip_reg) assert (issued == {N_AXES{1'b0}});
      if (trip_reg) assert (untrusted_reg);
      assert (trip_axis_reg < N_AXES);
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst)) begin
      // A rise while busy or a step toward an asserted switch trips on the next edge.
      if ($past(trip_now)) assert (trip_reg);
      // The alarm only ends on a clear while the switch that tripped was released.
      if ($past(trip_reg) && !trip_reg) assert ($past(clear) && !$past(held));
      // The switch named is one that caused the trip.
      if (!$past(trip_reg) && trip_reg)
        assert (trip_max_reg ? f_cmax_q[trip_axis_reg] : f_cmin_q[trip_axis_reg]);
      // Set only by a cause; the flag is cleared only by rst or a trust (SET_POSITION).
      if (!$past(trip_reg) && trip_reg) assert ($past(trip_now));
      if ($past(untrusted_reg) && !$past(trust)) assert (untrusted_reg);
      // A suppressed switch never trips (its HOME is armed).
      if (!$past(trip_reg) && trip_reg)
        assert (trip_max_reg ? !f_smax_q[trip_axis_reg] : !f_smin_q[trip_axis_reg]);
      cover (!$past(trip_reg) && trip_reg && $past(busy) && ($past(rise_min) != 0));
      cover ($past(trip_reg) && !trip_reg);
    end
`endif

endmodule

`default_nettype wire
