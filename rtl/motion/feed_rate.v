// feed_rate: the motion rate behind feed hold, resume and the feed / rapid overrides (docs/timing.md
// "Feed hold and overrides (the motion rate)"): a rate r in 0 .. 2^32 (2^32 = 100 %), a phase
// accumulator whose carry is `adv`, the per-clock enable of every motion generator, and the hold
// latch.
//
// Contract (values during clock t, the clock after edge t)
//   adv(t+1)  = 1 when acc(t) + r(t) >= 2^32; acc(t+1) = (acc(t) + r(t)) mod 2^32. A register:
//               the executor's tick gate starts at a flip-flop.
//   r         moves only at the edge that ends a period (p(t) = 2^PERIOD_LOG2 - 1; p counts from
//             rst): to cand(t), a register: cand(t) = r(t-1) moved toward target(t-1) by at most
//             ramp(t-1), equal to target(t-1) when within ramp(t-1) (r(t-1) = r(t) then: r
//             changed last a whole period before). cand is written only in the clock before the
//             period's last one (p = 2^PERIOD_LOG2 - 2), the only value r reads. The step is formed a clock ahead so that its
//             compares and the zero test of `stopped` are not one path.
//   target    0 while hold; rapid * 2^17 while `rapid_seg` (the executor's segment has code 0);
//             else feed * 2^17.
//   load       1-clock strobe (an accepted MOTION frame): feed, rapid, ramp take set_feed,
//             set_rapid, set_ramp on the edge after it; set_hold / set_resume are its flags.
//   hold_req, resume_req   1-clock strobes (the hold and cycle-start inputs); a hold request (frame
//             or input) wins over a resume in the same clock.
//   set_cancel   with load (MOTION CANCEL): a hold that ends in a flush: `cancel` is set with the
//             hold; in the first clock with cancel and r = 0, `flush` is high (cnc_core drops the
//             running segment and the queue as on an e-stop, positions kept) and on its edge cancel
//             and hold clear (a hold request in that clock keeps the hold). A resume does not end
//             the hold of a cancel in progress.
//   cancel_req   1-clock strobe (the probe trigger, rtl/machine/trigger_latch.v): a CANCEL as
//             set_cancel with load, without changing the rates or the ramp.
//   hold      the hold latch; stopped = (r == 0), a register.
// After rst: r = 2^32, acc = 0, adv = 1, p = 0, hold = 0, feed = rapid = 0x8000, ramp = RAMP0: adv
// is high in every clock until a MOTION frame or a hold request changes the target.
// The range checks (feed, rapid 1 .. 0x8000, ramp >= 1, not HOLD and RESUME together) are the
// frame decoder's; this block takes what it is given.
// Resources: 33-bit r and cand, 32-bit acc, 32-bit ramp, 2 x 16-bit rates, PERIOD_LOG2-bit
// counter; a 33-bit add (phase); r + ramp and r - ramp, each then compared with the target, in
// parallel with the compare of the target and r.
`default_nettype none

module feed_rate #(
    parameter PERIOD_LOG2 = 8,          // r moves once every 2^PERIOD_LOG2 clocks
    parameter [31:0] RAMP0 = 32'd219902  // ramp after rst
) (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [15:0] set_feed,
    input wire [15:0] set_rapid,
    input wire [31:0] set_ramp,
    input wire        set_hold,
    input wire        set_resume,
    input wire        set_cancel,
    input wire        hold_req,
    input wire        resume_req,
    input wire        cancel_req,
    input wire        rapid_seg,

    output wire        adv,
    output wire        hold,
    output wire        stopped,
    output wire        flush,
    output wire [32:0] rate
);

  generate
    if (PERIOD_LOG2 < 2 || PERIOD_LOG2 > 16) begin : g_bad_period
      feed_rate_illegal_PERIOD_LOG2_not_2_to_16 u_err ();
    end
    if (RAMP0 == 32'd0) begin : g_bad_ramp
      feed_rate_illegal_RAMP0_zero u_err ();
    end
  endgenerate

  localparam [32:0] ONE = 33'h1_0000_0000;

  reg [           32:0] r_reg;
  reg [           31:0] acc_reg;
  reg                   adv_reg;
  reg [PERIOD_LOG2-1:0] p_reg;
  reg                   hold_reg;
  reg [           15:0] feed_reg;
  reg [           15:0] rapid_reg;
  reg [           31:0] ramp_reg;
  reg                   stopped_reg;
  reg                   cancel_reg;
  wire                  flush_w = cancel_reg && stopped_reg;

  reg  [           32:0] cand_reg;
  wire [32:0] target = hold_reg ? 33'd0 : {rapid_seg ? rapid_reg : feed_reg, 17'd0};
  // r moved toward the target by at most the ramp: r + ramp and r - ramp (34 bits, the latter
  // negative when the ramp is larger than r), each compared with the target, and which applies
  wire        up = (target > r_reg);
  wire [33:0] r_up = {1'b0, r_reg} + {2'd0, ramp_reg};
  wire [33:0] r_dn = {1'b0, r_reg} - {2'd0, ramp_reg};
  wire        past_up = (r_up >= {1'b0, target});
  wire        past_dn = r_dn[33] || (r_dn <= {1'b0, target});
  wire [32:0] r_next = up ? (past_up ? target : r_up[32:0]) : (past_dn ? target : r_dn[32:0]);
  wire        period_end = (p_reg == {PERIOD_LOG2{1'b1}});
  // the clock before a period's last clock: the step that r takes at the period end is formed
  wire        period_last = (p_reg == {{(PERIOD_LOG2 - 1) {1'b1}}, 1'b0});
  wire [32:0] phase = {1'b0, acc_reg} + r_reg;

  always @(posedge clk) begin
    {adv_reg, acc_reg} <= phase;
    p_reg <= p_reg + {{(PERIOD_LOG2 - 1) {1'b0}}, 1'b1};
    if (period_last) cand_reg <= r_next;  // read only at the period's end
    if (period_end) begin
      r_reg       <= cand_reg;
      stopped_reg <= (cand_reg == 33'd0);
    end
    if (load) begin
      feed_reg  <= set_feed;
      rapid_reg <= set_rapid;
      ramp_reg  <= set_ramp;
    end
    if ((load && (set_hold || set_cancel)) || hold_req || cancel_req) hold_reg <= 1'b1;
    else if (flush_w || (((load && set_resume) || resume_req) && !cancel_reg)) hold_reg <= 1'b0;
    if ((load && set_cancel) || cancel_req) cancel_reg <= 1'b1;
    else if (flush_w) cancel_reg <= 1'b0;
    if (rst) begin
      r_reg       <= ONE;
      cand_reg    <= ONE;
      acc_reg     <= 32'd0;
      adv_reg     <= 1'b1;
      p_reg       <= {PERIOD_LOG2{1'b0}};
      hold_reg    <= 1'b0;
      feed_reg    <= 16'h8000;
      rapid_reg   <= 16'h8000;
      ramp_reg    <= RAMP0;
      stopped_reg <= 1'b0;
      cancel_reg  <= 1'b0;
    end
  end

  assign adv     = adv_reg;
  assign hold    = hold_reg;
  assign stopped = stopped_reg;
  assign flush   = flush_w;
  assign rate    = r_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set feed_rate: k-induction and cover). Reset in the first
  // clock; every input is free (the decoder's range checks assumed: feed, rapid 1 .. 0x8000,
  // ramp >= 1).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(*)
    if (load) begin
      assume (set_feed != 16'd0 && set_feed <= 16'h8000);
      assume (set_rapid != 16'd0 && set_rapid <= 16'h8000);
      assume (set_ramp != 32'd0);
    end
  reg [32:0] f_r_q;
  reg [31:0] f_ramp_q, f_ramp_qq;
  reg f_hold_q, f_hold_qq, f_rst_q, f_rst_qq, f_period_q;
  always @(posedge clk) begin
    f_r_q      <= r_reg;
    f_ramp_q   <= ramp_reg;
    f_ramp_qq  <= f_ramp_q;
    f_hold_q   <= hold_reg;
    f_hold_qq  <= f_hold_q;
    f_rst_q    <= rst;
    f_rst_qq   <= f_rst_q;
    f_period_q <= period_end;
  end
  function [33:0] f_absdiff;
    input [32:0] x, y;
    f_absdiff = (x >= y) ? ({1'b0, x} - {1'b0, y}) : ({1'b0, y} - {1'b0, x});
  endfunction
  always @(*)
    if (f_past_valid && !f_rst_q) begin
      // the rate stays within 0 .. 100 %; the registers stay in range
      assert (r_reg <= ONE);
      assert (cand_reg <= ONE);
      assert (feed_reg != 16'd0 && feed_reg <= 16'h8000);
      assert (rapid_reg != 16'd0 && rapid_reg <= 16'h8000);
      assert (ramp_reg != 32'd0);
      assert (stopped_reg == (r_reg == 33'd0));
      // a cancel is always a hold, and flushes only with the motion at rest
      if (cancel_reg) assert (hold_reg);
      if (flush) assert (r_reg == 33'd0);
      // the next step is at most the ramp away from the rate it was formed from, and never up
      // from a clock in hold
      if (period_end) begin
        assert (f_absdiff(cand_reg, f_r_q) <= {2'd0, f_ramp_q});
        if (f_hold_q) assert (cand_reg <= f_r_q);
      end
      // a hold never exceeds the configured deceleration: r changes only at a period end, and
      // then by at most the ramp in force when the step was formed; in a hold it never rises
      if (!f_period_q) assert (r_reg == f_r_q);
      else if (!f_rst_qq) begin
        assert (f_absdiff(r_reg, f_r_q) <= {2'd0, f_ramp_qq});
        if (f_hold_qq) assert (r_reg <= f_r_q);
      end
      // no tick while the rate is 0 for a whole clock
      if (f_r_q == 33'd0) assert (!adv_reg);
      // at 100 % every clock is a tick
      if (f_r_q == ONE) assert (adv_reg);
    end
  // The state worth seeing: a hold that brought the rate to 0, then a resume back to 100 %.
  // scripts/formal.sh (mode satcover) reads this file with FORMAL_COVER and asks yosys's SAT
  // solver for a trace that violates the assertion below, i.e. a trace that reaches the state
  // (the solver of the other modes does not finish on this block's arithmetic).
  reg f_seen_stop = 1'b0;
  always @(posedge clk) if (!rst && stopped_reg && hold_reg) f_seen_stop <= 1'b1;
`ifdef FORMAL_COVER
  always @(*) if (f_past_valid) assert (!(f_seen_stop && !hold_reg && r_reg == ONE));
`endif
`endif

endmodule

`default_nettype wire
