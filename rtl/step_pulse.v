// step_pulse: STEP/DIR pin driver for one axis, with runtime timing in clocks.
//
// step_req (1-clock strobe) -> STEP rises on the next clock edge and stays high exactly
// cfg_high clocks (>= 1), then low for at least cfg_low clocks (>= 1) before it can rise again.
// dir_wr (1-clock strobe) loads DIR from dir_in on the next edge. The caller (segment_executor)
// only writes DIR when hold_ok is high and waits DIR setup clocks before the next step_req, so this
// block only measures: hold_ok = at least cfg_hold clocks have passed since the last STEP rising
// edge (1 after reset). idle = STEP is low, its low time has elapsed and no step is pending: a
// step_req now rises at once.
// A step_req while not idle is a timing violation: it is not lost, it is issued as soon as the
// low time allows, and violation strobes (the executor's period clamp makes this unreachable;
// the strobe exists so a bench can prove it).
// Timing: STEP rising edge 1 clock after step_req.
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

endmodule

`default_nettype wire
