// trigger_latch: the homing and probing trigger (docs/machine.md "Homing and probing (hardware)"):
// armed by a TRIGGER frame, it watches the filtered limit switches (HOME) or the filtered probe
// (PROBE), latches the position counters at the clock of the edge and ends the motion.
//
// Contract
//   wr, wr_mode, wr_mask   an accepted TRIGGER frame (1-clock strobe) and its fields: mode 0
//                 DISARM, 1 HOME, 2 PROBE (wait for contact: the probe becomes asserted), 3 PROBE
//                 (wait for release: it becomes released); wr_mask {max, min} (bit a = min switch
//                 of axis a, N_AXES + a its max switch) the switches a HOME arms (0 otherwise:
//                 the decoder checks). HOME and PROBE arm: armed = 1, done = 0, fired = 0, every
//                 latched position 0, on the edge after wr. DISARM: armed = done = 0, mode 0;
//                 fired and latched keep their values. A wr wins over a fire in the same clock.
//   sw_rise       {max, min}: 1-clock strobes, the switch's filtered level rose (input_filter: the
//                 first clock of the asserted level; never for a switch not wired).
//   probe_q, probe_strobe   the filtered probe level (1 = asserted) and its change strobe.
//   position      the position counters (axis a in [32*a+:32]): in clock c, the count of the STEP
//                 rising edges up to and including edge c (segment_executor).
//   HOME          a fire of switch s in clock c: armed, mode HOME, s armed, not fired yet and
//                 sw_rise[s] (its filtered level rose: clock c is the first with it asserted). On
//                 edge c + 1: fired[s] = 1 and latched[axis of s] = position[axis] of clock c (the
//                 STEP rises of edges <= c; a STEP request of clock c rises on edge c + 1 and is
//                 not counted; cnc_core's limit block keeps the axis from stepping toward its
//                 asserted switch in clock c, so for a move toward the switch that is where the axis
//                 stays). When the fires of clock c complete the armed mask: done = 1, armed = 0 on
//                 edge c + 1 and `flush` is high in clock c + 1 (cnc_core: motion_abort, as a CANCEL
//                 flush: FIFO, prep and executor dropped, no fault, positions kept).
//   suppress      {max, min}: the armed switches of a HOME while armed and in the flush clock:
//                 cnc_core masks their hard-limit trips (unarmed switches still trip); the step
//                 block toward an asserted switch stays.
//   PROBE         a hit in clock c: armed, mode PROBE, probe_strobe and probe_q at the mode's
//                 level (an edge: a probe already at the level when armed never hits). On edge
//                 c + 1: every axis's latched = position of clock c, done = 1, armed = 0, and
//                 `cancel` is high in clock c + 1 (feed_rate: a CANCEL, the rate ramps to 0 with
//                 the ramp in force, then flushes).
//   A move that ends with the trigger armed leaves it armed (no contact, switch not found).
//   rst           synchronous: disarmed, done 0, fired 0, latched 0.
// Resources: 32 * N_AXES latch flops, 2 * N_AXES mask and fired flops, no arithmetic.
`default_nettype none

module trigger_latch #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire                wr,
    input wire [         1:0] wr_mode,
    input wire [2*N_AXES-1:0] wr_mask,

    input wire [2*N_AXES-1:0] sw_rise,
    input wire                probe_q,
    input wire                probe_strobe,
    input wire [32*N_AXES-1:0] position,

    output wire [2*N_AXES-1:0] suppress,
    output wire                flush,
    output wire                cancel,

    output wire                 armed,
    output wire                 done,
    output wire [          1:0] mode,
    output wire [ 2*N_AXES-1:0] fired,
    output wire [32*N_AXES-1:0] latched
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      trigger_latch_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  localparam [1:0] M_DISARM = 2'd0, M_HOME = 2'd1;

  reg armed_reg, done_reg, flush_reg, cancel_reg;
  reg [1:0] mode_reg;
  reg [2*N_AXES-1:0] mask_reg, fired_reg;
  reg [32*N_AXES-1:0] lat_reg;

  wire home = armed_reg && (mode_reg == M_HOME);
  wire [2*N_AXES-1:0] fire = sw_rise & mask_reg & ~fired_reg & {2 * N_AXES{home}};
  wire [2*N_AXES-1:0] fired_n = fired_reg | fire;
  wire home_done = (fire != {2 * N_AXES{1'b0}}) && (fired_n == mask_reg);
  wire hit = armed_reg && mode_reg[1] && probe_strobe && (probe_q == !mode_reg[0]);
  // axes whose position is latched in this clock
  wire [N_AXES-1:0] take = fire[N_AXES-1:0] | fire[2*N_AXES-1:N_AXES] | {N_AXES{hit}};

  integer a;
  always @(posedge clk) begin
    flush_reg  <= 1'b0;
    cancel_reg <= 1'b0;
    if (wr) begin
      mode_reg  <= wr_mode;
      armed_reg <= (wr_mode != M_DISARM);
      done_reg  <= 1'b0;
      if (wr_mode != M_DISARM) begin
        mask_reg  <= wr_mask;
        fired_reg <= {2 * N_AXES{1'b0}};
        lat_reg   <= {32 * N_AXES{1'b0}};
      end
    end else begin
      fired_reg <= fired_n;
      for (a = 0; a < N_AXES; a = a + 1)
        if (take[a]) lat_reg[32*a+:32] <= position[32*a+:32];
      if (home_done || hit) begin
        armed_reg <= 1'b0;
        done_reg  <= 1'b1;
      end
      flush_reg  <= home_done;
      cancel_reg <= hit;
    end
    if (rst) begin
      armed_reg  <= 1'b0;
      done_reg   <= 1'b0;
      flush_reg  <= 1'b0;
      cancel_reg <= 1'b0;
      mode_reg   <= M_DISARM;
      mask_reg   <= {2 * N_AXES{1'b0}};
      fired_reg  <= {2 * N_AXES{1'b0}};
      lat_reg    <= {32 * N_AXES{1'b0}};
    end
  end

  assign suppress = mask_reg & {2 * N_AXES{home || (flush_reg && mode_reg == M_HOME)}};
  assign flush    = flush_reg;
  assign cancel   = cancel_reg;
  assign armed    = armed_reg;
  assign done     = done_reg;
  assign mode     = mode_reg;
  assign fired    = fired_reg;
  assign latched  = lat_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set trigger_latch: k-induction and covers). Reset in the
  // first clock; every input free (the switch rise strobes too) except the filter's rule for the
  // probe (its strobe comes exactly when its level changes) and the decoder's (a HOME arms a
  // non-empty mask, the other modes none).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(*) begin
    if (wr && wr_mode == M_HOME) assume (wr_mask != {2 * N_AXES{1'b0}});
    if (wr && wr_mode != M_HOME) assume (wr_mask == {2 * N_AXES{1'b0}});
  end
  always @(posedge clk)
    if (f_past_valid) begin
      assume (probe_strobe == (probe_q != $past(probe_q)));
    end

  reg [32*N_AXES-1:0] f_pos_q;  // position of the previous clock
  reg [2*N_AXES-1:0] f_fire_q, f_sw_rise_q;
  reg f_hit_q, f_wr_q, f_probe_ok_q;
  always @(posedge clk) begin
    f_pos_q      <= position;
    f_fire_q     <= fire;
    f_sw_rise_q  <= sw_rise;
    f_hit_q      <= hit;
    f_wr_q       <= wr;
    f_probe_ok_q <= probe_strobe && (probe_q == !mode_reg[0]);
  end

  integer k;
  always @(*)
    if (f_past_valid && !rst) begin
      // invariants
      assert ((fired_reg & ~mask_reg) == {2 * N_AXES{1'b0}});
      if (armed_reg) assert (!done_reg && mode_reg != M_DISARM);
      if (armed_reg && mode_reg == M_HOME) assert (fired_reg != mask_reg);
      if (mode_reg == M_HOME) assert (mask_reg != {2 * N_AXES{1'b0}});
      if (flush_reg) assert (done_reg && mode_reg == M_HOME && fired_reg == mask_reg);
      if (cancel_reg) assert (done_reg && mode_reg[1]);
      // the suppressed switches are armed ones of a HOME in progress (or its flush clock)
      assert ((suppress & ~mask_reg) == {2 * N_AXES{1'b0}});
      if (suppress != {2 * N_AXES{1'b0}}) assert (mode_reg == M_HOME && (armed_reg || flush_reg));
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst) begin
      for (k = 0; k < N_AXES; k = k + 1) begin
        // The latch holds the position of the edge's clock: a latched value that changed (not by
        // arming) is the previous clock's position, in a clock with a fire of that axis or a hit.
        if (!f_wr_q && lat_reg[32*k+:32] != $past(lat_reg[32*k+:32])) begin
          assert (lat_reg[32*k+:32] == f_pos_q[32*k+:32]);
          assert (f_fire_q[k] || f_fire_q[N_AXES+k] || f_hit_q);
        end
        // ... and a fire or hit always latches it.
        if (!f_wr_q && (f_fire_q[k] || f_fire_q[N_AXES+k] || f_hit_q))
          assert (lat_reg[32*k+:32] == f_pos_q[32*k+:32]);
      end
      // No latch without an armed edge: a switch is marked fired only on its own rise while armed
      // in a HOME; a probe completes only on an edge to the wanted level while armed.
      if (!f_wr_q && fired_reg != $past(fired_reg))
        assert ((fired_reg & ~$past(fired_reg)) == (f_sw_rise_q & $past(mask_reg) &
                ~$past(fired_reg)) && $past(armed_reg) && $past(mode_reg) == M_HOME);
      if (!$past(done_reg) && done_reg)
        assert ($past(armed_reg) && !f_wr_q &&
                ($past(mode_reg) == M_HOME ? fired_reg == mask_reg : f_probe_ok_q));
      // The flush only after every armed switch fired (HOME), in the clock after the last fire.
      if (flush_reg) assert ($past(home_done) && fired_reg == mask_reg);
      if (cancel_reg) assert (f_hit_q);
    end
  // Covers: a HOME of two switches (X min, Y max) fired in different clocks completing, then a
  // PROBE (contact) completing. scripts/formal.sh (mode satcover) reads this file with
  // FORMAL_COVER and asks yosys's SAT solver for a trace that violates the assertion below.
  reg f_seen_home2 = 1'b0, f_seen_probe = 1'b0;
  always @(posedge clk) begin
    if (!rst && flush_reg && mask_reg[0] && mask_reg[N_AXES+1] && f_fire_q != mask_reg)
      f_seen_home2 <= 1'b1;
    if (!rst && f_seen_home2 && cancel_reg && mode_reg == 2'd2) f_seen_probe <= 1'b1;
  end
`ifdef FORMAL_COVER
  always @(*) if (f_past_valid) assert (!f_seen_probe);
`endif
`endif

endmodule

`default_nettype wire
