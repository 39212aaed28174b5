// heater_safety: the temperature checks of one heater channel (docs/heater.md "Safety").
//
// Contract
//   arm         1-clock strobe: a setpoint was written and the channel is enabled. On the next
//               eval the supervision state is chosen from that eval's temperature T (no runaway
//               or watch check on that eval): set > T + band -> WATCH (ref = T, timer 0);
//               set < T - band -> COOL; otherwise HOLD (timer 0).
//   eval        1-clock strobe: temp is this tick's reading; run the checks (while enable).
//   enable      low: state IDLE, timers 0, no checks.
//   temp, setpoint, tmin, tmax: Q11.4 s16. band, wrise: Q12.4 u16. rperiod, wperiod: ticks.
//   Checks on eval (enable high), each latching its fault bit:
//     bit 0 MINTEMP  temp < tmin;  bit 1 MAXTEMP temp > tmax;
//     bit 2 RUNAWAY  in HOLD, |temp - set| > band on rperiod consecutive evals (rperiod 0: off);
//     bit 3 HEATING  in WATCH, temp has not reached ref + wrise by the wperiod-th eval since
//                    the watch was (re)armed (wperiod 0: off). Reaching it re-arms the watch at
//                    the new temperature; reaching set - band moves to HOLD.
//     COOL moves to HOLD when temp <= set + band.
//   fault_clear 1-clock strobe: clears every bit (a fault detected on the same edge stays).
//   faults      registered: high from the eval edge that detects it (the channel forces its
//               heater low on the next edge).
//   holding     state is HOLD.
// rst is synchronous, active high (no fault, IDLE).
`default_nettype none

module heater_safety (
    input wire clk,
    input wire rst,

    input wire               arm,
    input wire               eval,
    input wire               enable,
    input wire signed [15:0] temp,
    input wire signed [15:0] setpoint,
    input wire signed [15:0] tmin,
    input wire signed [15:0] tmax,
    input wire        [15:0] band,
    input wire        [15:0] rperiod,
    input wire        [15:0] wrise,
    input wire        [15:0] wperiod,
    input wire               fault_clear,

    output wire [3:0] faults,
    output wire       holding
);

  localparam [1:0] Q_IDLE = 2'd0, Q_WATCH = 2'd1, Q_HOLD = 2'd2, Q_COOL = 2'd3;

  reg [1:0] q_reg;
  reg [3:0] faults_reg;
  reg signed [15:0] ref_reg;
  reg [15:0] wtimer_reg, rtimer_reg;
  reg arm_pend_reg;

  // The band compares, timers' next values and the faults found are block-local regs formed
  // only in an enabled eval clock, in the branch that reads them (the same logic as continuous
  // assignments; a simulator evaluates them only on the sample tick).
  always @(posedge clk) begin : seq
    reg signed [17:0] t18, s18, b18, r18, w18;
    reg above_band, below_band;
    reg [15:0] wtimer_next, rtimer_next;
    reg [3:0] found;
    found = 4'd0;
    if (eval && enable) begin
      t18         = {{2{temp[15]}}, temp};
      s18         = {{2{setpoint[15]}}, setpoint};
      b18         = {2'd0, band};
      r18         = {{2{ref_reg[15]}}, ref_reg};
      w18         = {2'd0, wrise};
      above_band  = (t18 > s18 + b18);  // temp > set + band
      below_band  = (t18 < s18 - b18);  // temp < set - band
      wtimer_next = wtimer_reg + 16'd1;
      rtimer_next = rtimer_reg + 16'd1;
      found[0]    = (temp < tmin);
      found[1]    = (temp > tmax);
      found[2]    = !arm_pend_reg && (q_reg == Q_HOLD) && (above_band || below_band) &&
                    (rperiod != 16'd0) && (rtimer_next >= rperiod);
      found[3]    = !arm_pend_reg && (q_reg == Q_WATCH) && below_band && (t18 < r18 + w18) &&
                    (wperiod != 16'd0) && (wtimer_next >= wperiod);
      if (arm) begin
        arm_pend_reg <= 1'b1;
      end else if (arm_pend_reg) begin
        arm_pend_reg <= 1'b0;
        ref_reg      <= temp;
        wtimer_reg   <= 16'd0;
        rtimer_reg   <= 16'd0;
        q_reg        <= below_band ? Q_WATCH : above_band ? Q_COOL : Q_HOLD;
      end else begin
        case (q_reg)
          Q_WATCH:
          if (!below_band) begin
            q_reg      <= Q_HOLD;
            rtimer_reg <= 16'd0;
          end else if (t18 >= r18 + w18) begin
            ref_reg    <= temp;
            wtimer_reg <= 16'd0;
          end else begin
            wtimer_reg <= wtimer_next;
          end
          Q_HOLD: rtimer_reg <= (above_band || below_band) ? rtimer_next : 16'd0;
          Q_COOL:
          if (!above_band) begin
            q_reg      <= Q_HOLD;
            rtimer_reg <= 16'd0;
          end
          default: q_reg <= Q_IDLE;
        endcase
      end
    end else if (!enable) begin
      q_reg        <= Q_IDLE;
      wtimer_reg   <= 16'd0;
      rtimer_reg   <= 16'd0;
      arm_pend_reg <= 1'b0;
    end else if (arm) begin
      arm_pend_reg <= 1'b1;
    end
    faults_reg <= (fault_clear ? 4'd0 : faults_reg) | found;
    if (rst) begin
      q_reg      <= Q_IDLE;
      arm_pend_reg <= 1'b0;
      faults_reg <= 4'd0;
      ref_reg    <= 16'sd0;
      wtimer_reg <= 16'd0;
      rtimer_reg <= 16'd0;
    end
  end

  assign faults  = faults_reg;
  assign holding = (q_reg == Q_HOLD);

endmodule

`default_nettype wire
