// heater_channel: one heater: its settings, controller (pid_incr), safety (heater_safety) and PWM
// output (pwm) (docs/heater.md, docs/protocol.md "Heater frames").
//
// Contract
//   cfg_wr      1-clock strobe: take mode, kp, ki, kd, umax, hyst, manual (HEATER_CONFIG). A mode
//               change restarts the controller; the PWM output follows the next sample.
//   set_wr      1-clock strobe: take set_value (HEATER_SETPOINT). set_value > 0 enables the
//               channel unless a fault of the channel is latched or kill is high; <= 0 disables it.
//               An enabling setpoint arms the safety supervision on the next clock.
//   safe_wr     1-clock strobe: take tmin, tmax, band, rperiod, wrise, wperiod (HEATER_SAFETY).
//   eval        1-clock strobe: temp is this sample's reading: the controller and the checks run.
//   kill        level (e-stop or watchdog latched): channel disabled, heater low.
//   fault_clear 1-clock strobe: clears the channel's fault bits (the channel stays disabled until
//               the next enabling setpoint).
//   heater      the pin: PWM of the controller output; low from the edge after a fault is
//               latched, after kill rises, or after the channel is disabled.
//   status      temperature s16, setpoint s16, duty u16 Q1.15 (0 while forced low), mode byte
//               {enabled, holding, 3'b0, mode}, faults byte {4'b0, HEATING, RUNAWAY, MAXTEMP,
//               MINTEMP}: 64 bits, temperature in [63:48].
// Reset values: the DEF_* parameters (safety) and mode OFF, gains 0, umax 0x8000, hysteresis
//   1 degC, manual 0, setpoint 0, disabled. rst is synchronous, active high.
`default_nettype none

module heater_channel #(
    parameter PWM_BITS     = 10,
    parameter PWM_DIV      = 4883,
    parameter DEF_TMIN     = 16'sd80,    // 5 degC
    parameter DEF_TMAX     = 16'sd4400,  // 275 degC
    parameter DEF_BAND     = 16'd64,     // 4 degC
    parameter DEF_RPERIOD  = 16'd40,
    parameter DEF_WRISE    = 16'd32,     // 2 degC
    parameter DEF_WPERIOD  = 16'd20
) (
    input wire clk,
    input wire rst,

    input wire        cfg_wr,
    input wire [ 2:0] cfg_mode,
    input wire [31:0] cfg_kp,
    input wire [31:0] cfg_ki,
    input wire [31:0] cfg_kd,
    input wire [15:0] cfg_umax,
    input wire [15:0] cfg_hyst,
    input wire [15:0] cfg_manual,

    input wire        set_wr,
    input wire [15:0] set_value,

    input wire        safe_wr,
    input wire [15:0] safe_tmin,
    input wire [15:0] safe_tmax,
    input wire [15:0] safe_band,
    input wire [15:0] safe_rperiod,
    input wire [15:0] safe_wrise,
    input wire [15:0] safe_wperiod,

    input wire        eval,
    input wire [15:0] temp,
    input wire        kill,
    input wire        fault_clear,

    output wire        heater,
    output wire [63:0] status,
    output wire [ 3:0] faults,
    output wire [PWM_BITS:0] duty,  // PWM counts the controller asks for (before force-off)
    output wire        pid_done,    // 1-clock strobe: a new controller output
    output wire        enabled
);

  reg [2:0] mode_reg;
  reg [31:0] kp_reg, ki_reg, kd_reg;
  reg [15:0] umax_reg, hyst_reg, manual_reg;
  reg signed [15:0] set_reg, temp_reg;
  reg signed [15:0] tmin_reg, tmax_reg;
  reg [15:0] band_reg, rperiod_reg, wrise_reg, wperiod_reg;
  reg enable_reg, arm_reg, restart_reg;
  reg [PWM_BITS:0] duty_reg;

  wire [3:0] faults_w;
  wire holding;
  /* verilator lint_off UNUSEDSIGNAL */
  wire [28:0] u;  // Q1.28: the PWM takes the top PWM_BITS + 1 bits
  /* verilator lint_on UNUSEDSIGNAL */
  wire u_done;
  /* verilator lint_off UNUSEDSIGNAL */
  wire pid_busy, pwm_start;
  /* verilator lint_on UNUSEDSIGNAL */
  wire [PWM_BITS:0] active;

  wire set_pos = !set_value[15] && (set_value != 16'd0);
  wire force_off = !enable_reg || (faults_w != 4'd0) || kill;

  always @(posedge clk) begin
    arm_reg     <= 1'b0;
    restart_reg <= 1'b0;
    if (cfg_wr) begin
      mode_reg    <= cfg_mode;
      kp_reg      <= cfg_kp;
      ki_reg      <= cfg_ki;
      kd_reg      <= cfg_kd;
      umax_reg    <= cfg_umax;
      hyst_reg    <= cfg_hyst;
      manual_reg  <= cfg_manual;
      restart_reg <= (cfg_mode != mode_reg);
    end
    if (set_wr) begin
      set_reg <= set_value;
      if (set_pos && faults_w == 4'd0 && !kill) begin
        enable_reg  <= 1'b1;
        arm_reg     <= 1'b1;
        restart_reg <= !enable_reg;
      end else begin
        enable_reg <= 1'b0;
      end
    end
    if (safe_wr) begin
      tmin_reg    <= safe_tmin;
      tmax_reg    <= safe_tmax;
      band_reg    <= safe_band;
      rperiod_reg <= safe_rperiod;
      wrise_reg   <= safe_wrise;
      wperiod_reg <= safe_wperiod;
    end
    if (eval) temp_reg <= temp;
    if (faults_w != 4'd0 || kill) enable_reg <= 1'b0;
    if (u_done) duty_reg <= u[28:28-PWM_BITS];
    if (rst) begin
      mode_reg    <= 3'd0;
      kp_reg      <= 32'd0;
      ki_reg      <= 32'd0;
      kd_reg      <= 32'd0;
      umax_reg    <= 16'h8000;
      hyst_reg    <= 16'd16;
      manual_reg  <= 16'd0;
      set_reg     <= 16'sd0;
      temp_reg    <= 16'sd0;
      tmin_reg    <= DEF_TMIN;
      tmax_reg    <= DEF_TMAX;
      band_reg    <= DEF_BAND;
      rperiod_reg <= DEF_RPERIOD;
      wrise_reg   <= DEF_WRISE;
      wperiod_reg <= DEF_WPERIOD;
      enable_reg  <= 1'b0;
      arm_reg     <= 1'b0;
      restart_reg <= 1'b0;
      duty_reg    <= {(PWM_BITS + 1) {1'b0}};
    end
  end

  // The controller and the checks see this sample's temperature on the eval edge (temp input).
  pid_incr u_pid (
      .clk     (clk),
      .rst     (rst),
      .start   (eval),
      .enable  (enable_reg && !kill && faults_w == 4'd0),
      .restart (restart_reg),
      .mode    (mode_reg),
      .temp    (temp),
      .setpoint(set_reg),
      .kp      (kp_reg),
      .ki      (ki_reg),
      .kd      (kd_reg),
      .umax    (umax_reg),
      .hyst    (hyst_reg),
      .manual  (manual_reg),
      .u       (u),
      .done    (u_done),
      .busy    (pid_busy)
  );

  heater_safety u_safe (
      .clk        (clk),
      .rst        (rst),
      .arm        (arm_reg),
      .eval       (eval),
      .enable     (enable_reg),
      .temp       (eval ? temp : temp_reg),
      .setpoint   (set_reg),
      .tmin       (tmin_reg),
      .tmax       (tmax_reg),
      .band       (band_reg),
      .rperiod    (rperiod_reg),
      .wrise      (wrise_reg),
      .wperiod    (wperiod_reg),
      .fault_clear(fault_clear),
      .faults     (faults_w),
      .holding    (holding)
  );

  pwm #(
      .PWM_BITS(PWM_BITS),
      .PWM_DIV (PWM_DIV)
  ) u_pwm (
      .clk         (clk),
      .rst         (rst),
      .duty        (duty_reg),
      .force_off   (force_off),
      .out         (heater),
      .period_start(pwm_start),
      .active      (active)
  );

  wire [15:0] duty_q15 = force_off ? 16'd0 : ({{(15 - PWM_BITS) {1'b0}}, active} << (15 - PWM_BITS));

  assign status   = {temp_reg, set_reg, duty_q15, enable_reg, holding, 3'd0, mode_reg, 4'd0, faults_w};
  assign faults   = faults_w;
  assign duty     = duty_reg;
  assign pid_done = u_done;
  assign enabled  = enable_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal/heater_channel.ys, k-induction): the heater pin is low on
  // every clock after one in which a fault of the channel was latched or kill (e-stop, watchdog)
  // was high; a latched fault stays latched until fault_clear; the channel is not enabled again
  // while a fault is latched (nothing restarts until cleared and a new setpoint is sent).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst) begin
      if ($past(faults_w) != 4'd0 || $past(kill)) assert (!heater);
      if ($past(faults_w) != 4'd0) assert (!enable_reg);
      if (!$past(fault_clear)) assert ((faults_w & $past(faults_w)) == $past(faults_w));
      if (!$past(enable_reg) && !$past(set_wr)) assert (!enable_reg);
    end
`endif

endmodule

`default_nettype wire
