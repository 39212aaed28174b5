// step_pulse: STEP/DIR pin driver of one axis, timing in clocks set at run time (docs/timing.md
// "STEP/DIR per move").
//
// Contract
//   step_req   1-clock strobe: STEP rises on the next edge, stays high exactly cfg_high clocks,
//              then low at least cfg_low clocks before it may rise again (a setting of 0 acts
//              as 1). A step_req while not idle is not lost: it is issued as soon as the low time
//              allows, and violation strobes (segment_executor's period clamp keeps it from
//              happening; the strobe lets a bench prove that).
//   dir_wr     1-clock strobe: DIR takes dir_in on the next edge. The block does not enforce DIR
//              hold or setup; the caller writes DIR only while hold_ok and waits DIR setup clocks
//              before the next step_req.
//   hold_ok    at least cfg_hold clocks since the last STEP rise (before the first step: since
//              rst was released).
//   idle       STEP low, its low time elapsed, no step pending: a step_req now rises at once.
// Timing: STEP rises 1 clock after step_req.
`default_nettype none

module step_pulse (
    input wire clk,
    input wire rst,

    input wire [15:0] cfg_high,  // STEP high time in clocks, 1..65535 (0 is treated as 1)
    input wire [15:0] cfg_low,   // minimum STEP low time in clocks, 1..65535 (0 is treated as 1)
    input wire [15:0] cfg_hold,  // DIR hold after a STEP rising edge, clocks

    input wire step_req,
    input wire dir_in,
    input wire dir_wr,

    output wire step,
    output wire dir,
    output wire idle,       // STEP low and low time elapsed, nothing pending
    output wire hold_ok,
    output wire violation   // 1-clock strobe
);

  reg        step_reg;
  reg        dir_reg;
  reg [15:0] cnt_reg;       // clocks left in the current high or low phase
  reg        pending_reg;
  reg [15:0] hold_cnt_reg;  // clocks since the last rising edge, saturating at cfg_hold
  reg        violation_reg;

  wire [15:0] high_clks = (cfg_high == 16'd0) ? 16'd1 : cfg_high;
  wire [15:0] low_clks = (cfg_low == 16'd0) ? 16'd1 : cfg_low;
  wire        phase_done = (cnt_reg == 16'd0);
  wire        can_rise = !step_reg && phase_done;
  wire        want = step_req || pending_reg;

  always @(posedge clk) begin
    violation_reg <= 1'b0;
    if (dir_wr) dir_reg <= dir_in;
    if (hold_cnt_reg < cfg_hold) hold_cnt_reg <= hold_cnt_reg + 16'd1;

    if (step_reg) begin
      if (cnt_reg == 16'd1) begin
        step_reg <= 1'b0;
        cnt_reg  <= low_clks - 16'd1;
      end else begin
        cnt_reg <= cnt_reg - 16'd1;
      end
    end else if (!phase_done) begin
      cnt_reg <= cnt_reg - 16'd1;
    end

    if (want && can_rise) begin
      step_reg     <= 1'b1;
      cnt_reg      <= high_clks;
      pending_reg  <= 1'b0;
      hold_cnt_reg <= (cfg_hold == 16'd0) ? 16'd0 : 16'd1;
    end else if (step_req) begin
      pending_reg   <= 1'b1;
      violation_reg <= 1'b1;
    end

    if (rst) begin
      step_reg      <= 1'b0;
      dir_reg       <= 1'b0;
      cnt_reg       <= 16'd0;
      pending_reg   <= 1'b0;
      hold_cnt_reg  <= 16'd0;
      violation_reg <= 1'b0;
    end
  end

  assign step      = step_reg;
  assign dir       = dir_reg;
  assign idle      = can_rise && !pending_reg;
  assign hold_ok   = (hold_cnt_reg >= cfg_hold);
  assign violation = violation_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh, k-induction). Assumes: reset in the first clock, the
  // configuration stable. Monitors count clocks in the machine's terms; the asserts are the
  // contract of the top comment.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  reg [47:0] f_cfg_q;
  always @(posedge clk) f_cfg_q <= {cfg_high, cfg_low, cfg_hold};
  always @(*) if (f_past_valid) assume ({cfg_high, cfg_low, cfg_hold} == f_cfg_q);
`ifdef FORMAL_DIR
  // For the executor's DIR timing proof (scripts/formal/executor_dir.ys): no STEP timing violation,
  // i.e. no step request while a pulse or its low time is in progress, so nothing is ever pending.
  always @(*) assume (!pending_reg);
`endif

  reg        f_pulsed;    // a STEP pulse has ended since reset
  reg        f_rose;      // a STEP rising edge happened since reset
  reg [16:0] f_hi;        // clocks STEP has been high, counting this one
  reg [16:0] f_lo;        // clocks STEP has been low since the last pulse, saturating at low_clks
  reg [16:0] f_since;     // clocks since the last rising edge, saturating at 0x10000
  always @(posedge clk) begin
    if (step_reg && !(step_reg && cnt_reg == 16'd1)) f_hi <= f_hi + 17'd1;
    if (!step_reg && f_lo < {1'b0, low_clks}) f_lo <= f_lo + 17'd1;
    if (f_since != 17'h10000) f_since <= f_since + 17'd1;
    if (step_reg && cnt_reg == 16'd1) begin
      f_pulsed <= 1'b1;
      f_lo     <= 17'd1;
    end
    if (want && can_rise) begin
      f_rose  <= 1'b1;
      f_hi    <= 17'd1;
      f_since <= 17'd0;
    end
    if (rst) begin
      f_pulsed <= 1'b0;
      f_rose   <= 1'b0;
      f_hi     <= 17'd0;
      f_lo     <= 17'd0;
      f_since  <= 17'd0;
    end
  end

  always @(*)
    if (f_past_valid) begin
      // Induction invariants tying the monitors to the counters.
      if (step_reg) begin
        assert (f_rose);
        assert (f_hi >= 17'd1 && f_hi <= {1'b0, high_clks});
        assert ({1'b0, cnt_reg} == {1'b0, high_clks} - f_hi + 17'd1);
      end else if (f_pulsed) begin
        assert (f_lo >= 17'd1 && f_lo <= {1'b0, low_clks});
        assert ({1'b0, cnt_reg} == {1'b0, low_clks} - f_lo);
      end else begin
        assert (cnt_reg == 16'd0);
      end
      if (f_pulsed) assert (f_rose);
      assert (hold_cnt_reg <= cfg_hold);
      assert (f_since <= 17'h10000);
      if (f_rose && cfg_hold != 16'd0)
        assert ({1'b0, hold_cnt_reg} == ((f_since + 17'd1 >= {1'b0, cfg_hold}) ?
                                         {1'b0, cfg_hold} : f_since + 17'd1));
      if (f_rose && step_reg) assert (f_since + 17'd1 == f_hi);
      if (violation_reg) assert (pending_reg);
      // hold_ok: a DIR write issued now lands at least cfg_hold clocks after the last rising edge.
      if (hold_ok && f_rose) assert (f_since + 17'd1 >= {1'b0, cfg_hold});
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst)) begin
      // STEP high lasts exactly cfg_high clocks (0 treated as 1).
      if ($past(step_reg) && !step_reg) assert ($past(f_hi) == {1'b0, $past(high_clks)});
      // STEP low lasts at least cfg_low clocks between pulses (0 treated as 1).
      if (!$past(step_reg) && step_reg && $past(f_pulsed))
        assert ($past(f_lo) >= {1'b0, $past(low_clks)});
      // STEP rises exactly one clock after a request when idle.
      if ($past(step_req) && $past(idle)) assert (step_reg && f_hi == 17'd1);
      // DIR changes only on dir_wr, and then to dir_in.
      if ($past(dir_wr)) assert (dir_reg == $past(dir_in));
      else assert (dir_reg == $past(dir_reg));
    end
`endif

endmodule

`default_nettype wire
