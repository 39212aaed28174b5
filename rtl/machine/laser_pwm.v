// laser_pwm: the spindle_pwm pin (laser power on a laser machine, spindle speed on a mill): a PWM of
// 256 counts of DIV clocks whose periods start when the laser enable rises, with the duty that
// laser_scale computes from samples taken LAT + 1 clocks before each period (docs/machine.md
// "Laser and spindle PWM").
//
// Contract (position p = the clock's place in the running period, 0 .. 256 * DIV - 1)
//   en        the laser pin (cnc_core's `laser`: enable and gate). out is low in every clock with
//             en low, combinationally; en low stops the period.
//   sample    1-clock strobe to laser_scale (its start): in the first clock of en high after a
//             clock with en low (or after rst), and at p = 256 * DIV - 1 - LAT of a running
//             period.
//   duty, done   laser_scale's result (0 .. 255; 255 = always high) and its strobe: the first
//             clock with done after the en-rise sample starts the period (p = 0 in the next
//             clock) with that duty; at the edge ending p = 256 * DIV - 1 the next period takes
//             the duty then held (the sample of p = 256 * DIV - 1 - LAT, LAT clocks later).
//   out       high for the first `duty` counts of each period (duty 255: the whole period) while
//             en stays high: the first rise LAT + 1 clocks after en's.
// DIV >= 1 and 256 * DIV > LAT + 1 (else laser_pwm_illegal_<rule>, a module that does not exist).
// No divider on a clocked path (the sample position is an elaboration constant). rst is
// synchronous, active high.
`default_nettype none
`include "fpgacnc_spec.vh"

module laser_pwm #(
    parameter DIV = 195,
    parameter LAT = `FPGACNC_DEF_LASER_SCALE_CLKS
) (
    input wire clk,
    input wire rst,

    input  wire       en,
    output wire       sample,
    input  wire [7:0] duty,
    input  wire       done,
    output wire       out
);

  localparam integer PERIOD = 256 * DIV;
  localparam integer SPOS = PERIOD - 1 - LAT;  // where the scaler starts for the next period
  localparam integer SPOS_I = (SPOS < 0) ? 0 : SPOS;
  localparam integer DIV_I = (DIV < 1) ? 1 : DIV;
  localparam DW = (DIV_I > 1) ? $clog2(DIV_I) : 1;
  localparam integer SC_I = SPOS_I / DIV_I;
  localparam integer SD_I = SPOS_I % DIV_I;
  localparam integer DIV_LAST_I = DIV_I - 1;
  localparam [DW-1:0] DIV_LAST = DIV_LAST_I[DW-1:0];
  localparam [DW-1:0] SD = SD_I[DW-1:0];
  localparam [7:0] SC = SC_I[7:0];

  generate
    if (DIV < 1) begin : g_bad_div
      laser_pwm_illegal_DIV_below_1 u_err ();
    end
    if (PERIOD <= LAT + 1) begin : g_bad_period
      laser_pwm_illegal_period_not_above_LAT_plus_1 u_err ();
    end
  endgenerate

  reg          run_reg;  // a period is running
  reg          wait_reg;  // en rose: waiting for the scaler's first result
  reg [DW-1:0] div_reg;
  reg [   7:0] cnt_reg;
  reg [   8:0] active_reg;  // 0 .. 256 counts
  reg          out_reg;

  wire [   8:0] duty9 = (duty == 8'hFF) ? 9'd256 : {1'b0, duty};
  wire          div_wrap = (div_reg == DIV_LAST);
  wire          boundary = div_wrap && (cnt_reg == 8'hFF);
  wire [   7:0] cnt_next = div_wrap ? cnt_reg + 8'd1 : cnt_reg;
  wire [   8:0] duty_next = boundary ? duty9 : active_reg;
  wire          sample_start = en && !run_reg && !wait_reg;
  wire          sample_run = run_reg && (cnt_reg == SC) && (div_reg == SD);

  always @(posedge clk) begin
    if (run_reg) begin
      div_reg    <= div_wrap ? {DW{1'b0}} : div_reg + 1'b1;
      cnt_reg    <= cnt_next;
      active_reg <= duty_next;
      out_reg    <= ({1'b0, cnt_next} < duty_next);
    end
    if (sample_start) wait_reg <= 1'b1;
    if (wait_reg && done) begin
      run_reg    <= 1'b1;
      wait_reg   <= 1'b0;
      div_reg    <= {DW{1'b0}};
      cnt_reg    <= 8'd0;
      active_reg <= duty9;
      out_reg    <= (duty9 != 9'd0);
    end
    if (!en || rst) begin
      run_reg    <= 1'b0;
      wait_reg   <= 1'b0;
      div_reg    <= {DW{1'b0}};
      cnt_reg    <= 8'd0;
      active_reg <= 9'd0;
      out_reg    <= 1'b0;
    end
  end

  assign sample = sample_start || sample_run;
  assign out    = out_reg && en;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set laser_pwm: induction with Yosys's SAT engine, and a
  // cover trace). Reset in the first clock; en, duty and done are free. f_hi counts the clocks of
  // the running period so far in which out was high.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  reg [16:0] f_hi;
  always @(posedge clk) begin
    if (run_reg && out_reg) f_hi <= f_hi + 17'd1;
    if ((run_reg && boundary) || (wait_reg && done) || !en || rst) f_hi <= 17'd0;
  end

  // The high clocks an exact PWM has had before the clock at (cnt_reg, div_reg) of a period of
  // duty active_reg.
  localparam [16:0] F_DIV = DIV_I;
  wire [16:0] f_hi_want = ({1'b0, cnt_reg} < active_reg) ?
      {9'd0, cnt_reg} * F_DIV + {{(17 - DW) {1'b0}}, div_reg} : {8'd0, active_reg} * F_DIV;

  always @(*) begin
    // out is low whenever en is low, in the same clock.
    if (!en) assert (!out);
    if (f_past_valid) begin
      assert (!(run_reg && wait_reg));
      assert (active_reg <= 9'd256);
      assert (div_reg <= DIV_LAST);
      // Out of a period everything is at rest: no pulse before the first duty is known.
      if (!run_reg) assert (!out_reg && cnt_reg == 8'd0 && div_reg == {DW{1'b0}} && active_reg == 9'd0);
      // out in each clock of a period: high for the first `active` counts, low after them...
      assert (out_reg == ({1'b0, cnt_reg} < active_reg));
      // ... so the high time so far is exactly that of a PWM of this duty: at the end of a
      // period, duty * DIV clocks (256 * DIV at duty 255).
      if (run_reg) assert (f_hi == f_hi_want);
      else assert (f_hi == 17'd0);
    end
  end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && $past(en) && en) begin
      // A period starts only on the scaler's result while waiting for it, with its duty.
      if (run_reg && !$past(run_reg)) begin
        assert ($past(wait_reg && done));
        assert (active_reg == $past(duty9));
      end
      // The duty changes only where a period ends, to the scaler's result held then.
      if ($past(run_reg) && run_reg) begin
        if ($past(boundary)) assert (active_reg == $past(duty9));
        else assert (active_reg == $past(active_reg));
      end
    end

  // Cover: a period of duty 1 ending, and the next one starting at duty 255 (always high).
  // scripts/formal.sh (mode satcover) reads this file with FORMAL_COVER and asks Yosys's SAT
  // solver for a trace that violates the assertion below.
  reg f_seen_end = 1'b0, f_seen_next = 1'b0;
  always @(posedge clk) begin
    if (!rst && en && run_reg && boundary && active_reg == 9'd1) f_seen_end <= 1'b1;
    if (!rst && f_seen_end && run_reg && active_reg == 9'd256 && cnt_reg == 8'd1) f_seen_next <= 1'b1;
    if (rst) begin
      f_seen_end  <= 1'b0;
      f_seen_next <= 1'b0;
    end
  end
`ifdef FORMAL_COVER
  always @(*) if (f_past_valid) assert (!f_seen_next);
`endif
`endif

endmodule

`default_nettype wire
