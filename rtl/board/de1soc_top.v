// de1soc_top: Terasic DE1-SoC board top (protocols v1 and v2, N_AXES = 2), with the original
// controller's pin names (docs/architecture.md "Pins"): 50 MHz clk, KEY[0] as rst_n, USB-UART on GPIO_0[0..1],
// X/Y STEP/DIR and the laser enable on GPIO_0[2..6].
//   LEDR[0] busy, LEDR[1] laser, LEDR[2] dir_x, LEDR[3] dir_y, LEDR[4] v2 mode, LEDR[5] a fault
//   is latched (STEP timing violation, e-stop, heater, watchdog: until FAULT_CLEAR), LEDR[7]
//   heartbeat (1 Hz),
//   LEDR[8] a framing error was seen, LEDR[9] a packet was dropped (watchdog or overrun).
//   HEX5 last motion code, HEX4 'b' busy / '0' idle, HEX3-2 packet count (low byte),
//   HEX1-0 last feed (low byte), as on the original.
// Heaters (docs/heater.md): heater_hotend on GPIO_0[7], heater_bed on GPIO_0[8] (MOSFET gate
// drivers), e-stop input estop_n on GPIO_0[9] (active low: a normally-closed switch to ground
// with a pull-up, so a broken wire stops the machine), the on-board LTC2308 ADC on its dedicated
// pins ADC_CONVST/ADC_SCK/ADC_SDI/ADC_SDO (thermistors on ADC inputs 0 and 1). LEDR[6] heater 0
// or 1 on.
// Machine outputs (OUTPUT frames, docs/protocol.md "OUTPUT"; pins in docs/architecture.md):
// coolant_flood GPIO_0[10], coolant_mist GPIO_0[11], fan GPIO_0[12] (PWM at about FAN_PWM_HZ),
// dout[0..3] GPIO_0[13..16]; high = on, all low after reset and on e-stop.
// Limit switches (docs/machine.md): lim_x_min GPIO_0[17], lim_x_max GPIO_0[18], lim_y_min
// GPIO_0[19], lim_y_max GPIO_0[20], weak pull-ups on: a normally-closed switch to ground reads
// high when pressed or when its wire breaks (LIMIT_ACTIVE_LOW 0). LIMIT_ENABLE (bit 0 x min, 1 y
// min, 16 x max, 17 y max) says which are wired; the default (spec/protocol.toml) is none, so a
// board without switches (whose pulled-up pins read "pressed") still moves.
// Feed hold and cycle start (docs/machine.md): the push buttons KEY[1] (hold_n) and KEY[2]
// (start_n), active low (the board's buttons read low while pressed and are debounced on the
// board; the core filters them again).
// Probe (docs/machine.md "Homing and probing (hardware)"): probe_n GPIO_0[21], weak pull-up on,
// active low (PROBE_ACTIVE_LOW 1): a touch plate or a normally-open probe switch to ground reads
// low at contact; an unconnected pin reads high, released, so PROBE_ENABLE is 1 by default.
// Laser power / spindle speed (docs/machine.md "Laser and spindle PWM"): spindle_pwm GPIO_0[22],
// PWM at about LASER_PWM_HZ while `laser` is high (M3 / M4 S), low otherwise.
// The reset button is synchronized (two flops) and released synchronously.
// Its cnc_core is the configuration full-2axis of spec/configs.toml (fpgacnc_configs.vh).
`default_nettype none
`include "fpgacnc_configs.vh"
`include "fpgacnc_spec.vh"

module de1soc_top #(
    parameter CLK_HZ = 50_000_000,
    parameter BAUD   = 115_200,
    parameter FAN_PWM_HZ = 1000,
    parameter LASER_PWM_HZ = `FPGACNC_DEF_LASER_PWM_HZ,
    parameter LIMIT_FILTER_CLKS = `FPGACNC_DEF_LIMIT_FILTER_CLKS,
    parameter [31:0] LIMIT_ENABLE = `FPGACNC_DEF_LIMIT_ENABLE,
    parameter [31:0] LIMIT_ACTIVE_LOW = `FPGACNC_DEF_LIMIT_ACTIVE_LOW,
    parameter PROBE_FILTER_CLKS = `FPGACNC_DEF_PROBE_FILTER_CLKS,
    parameter PROBE_ENABLE = 1,
    parameter PROBE_ACTIVE_LOW = 1
) (
    input  wire       clk,
    input  wire       rst_n,
    input  wire       rx,
    output wire       tx,
    output wire       dir_x,
    output wire       step_x,
    output wire       dir_y,
    output wire       step_y,
    output wire       laser,
    output wire       coolant_flood,
    output wire       coolant_mist,
    output wire       fan,
    output wire [3:0] dout,
    output wire       spindle_pwm,
    output wire [9:0] LEDR,
    output wire [6:0] HEX0,
    output wire [6:0] HEX1,
    output wire [6:0] HEX2,
    output wire [6:0] HEX3,
    output wire [6:0] HEX4,
    output wire [6:0] HEX5,
    input  wire       estop_n,
    input  wire       lim_x_min,
    input  wire       lim_x_max,
    input  wire       lim_y_min,
    input  wire       lim_y_max,
    input  wire       hold_n,
    input  wire       start_n,
    input  wire       probe_n,
    output wire       heater_hotend,
    output wire       heater_bed,
    output wire       ADC_CONVST,
    output wire       ADC_SCK,
    output wire       ADC_SDI,
    input  wire       ADC_SDO
);

  localparam integer HALF_SECOND = CLK_HZ / 2;
  localparam HB_W = $clog2(HALF_SECOND);

  reg [1:0] rst_sync_reg = 2'b11;
  always @(posedge clk) rst_sync_reg <= {rst_sync_reg[0], ~rst_n};
  wire rst = rst_sync_reg[1];

  wire [1:0] step, dir;
  wire busy, running, seg_start, seg_done;
  wire [63:0] position;
  wire [1:0] last_code;
  wire [15:0] last_feed, packet_count, frame_errors, timeouts, overruns, violations;
  wire [31:0] last_period, numerator_x, numerator_y;
  wire [15:0] fifo_level, frames_ok, crc_errors, length_errors, unknown_types, noise_bytes;
  wire [15:0] clamped, naks;
  wire [7:0] next_seq, faults;
  wire v2_mode;
  wire rx_partial;
  wire [31:0] segments_done;
  wire [1:0] heater_w;
  wire [3:0] limit_state;
  wire limit_trip;
  wire probe_state;
  assign heater_hotend = heater_w[0];
  assign heater_bed    = heater_w[1];

  cnc_core #(
      .CLK_HZ    (CLK_HZ),
      .BAUD      (BAUD),
      .N_AXES    (`FPGACNC_CFG_FULL_2AXIS_N_AXES),
      .PROTO_V2  (`FPGACNC_CFG_FULL_2AXIS_PROTO_V2),
      .PROFILES  (`FPGACNC_CFG_FULL_2AXIS_PROFILES),
      .ARCS      (`FPGACNC_CFG_FULL_2AXIS_ARCS),
      .HEATERS   (`FPGACNC_CFG_FULL_2AXIS_HEATERS),
      .OUTPUTS   (`FPGACNC_CFG_FULL_2AXIS_OUTPUTS),
      .TRIGGER   (`FPGACNC_CFG_FULL_2AXIS_TRIGGER),
      .LEAN_TRIM (`FPGACNC_CFG_FULL_2AXIS_LEAN_TRIM),
      .STEP_CFG  (`FPGACNC_CFG_FULL_2AXIS_STEP_CFG),
      .FAN_PWM_HZ(FAN_PWM_HZ),
      .LASER_PWM_HZ(LASER_PWM_HZ),
      .LIMIT_FILTER_CLKS(LIMIT_FILTER_CLKS),
      .LIMIT_ENABLE     (LIMIT_ENABLE),
      .LIMIT_ACTIVE_LOW (LIMIT_ACTIVE_LOW),
      .BUTTON_ACTIVE_LOW(2'b11),
      .PROBE_FILTER_CLKS(PROBE_FILTER_CLKS),
      .PROBE_ENABLE     (PROBE_ENABLE),
      .PROBE_ACTIVE_LOW (PROBE_ACTIVE_LOW)
  ) u_core (
      .clk         (clk),
      .rst         (rst),
      .rx          (rx),
      .tx          (tx),
      .step        (step),
      .dir         (dir),
      .laser       (laser),
      .coolant_flood(coolant_flood),
      .coolant_mist (coolant_mist),
      .fan          (fan),
      .dout         (dout),
      .spindle_pwm  (spindle_pwm),
      .estop       (!estop_n),
      .limit_min   ({lim_y_min, lim_x_min}),
      .limit_max   ({lim_y_max, lim_x_max}),
      .hold_in     (hold_n),
      .start_in    (start_n),
      .probe_in    (probe_n),
      .heater      (heater_w),
      .adc_convst  (ADC_CONVST),
      .adc_sck     (ADC_SCK),
      .adc_sdi     (ADC_SDI),
      .adc_sdo     (ADC_SDO),
      .cfg_wr      (1'b0),
      .cfg_addr    (8'd0),
      .cfg_wdata   (16'd0),
      .busy        (busy),
      .running     (running),
      .seg_start   (seg_start),
      .seg_done    (seg_done),
      .position    (position),
      .last_code   (last_code),
      .last_feed   (last_feed),
      .last_period (last_period),
      .packet_count(packet_count),
      .frame_errors(frame_errors),
      .timeouts    (timeouts),
      .overruns    (overruns),
      .violations  (violations),
      .numerator_x (numerator_x),
      .numerator_y (numerator_y),
      .fifo_level   (fifo_level),
      .next_seq     (next_seq),
      .v2_mode      (v2_mode),
      .rx_partial   (rx_partial),
      .segments_done(segments_done),
      .faults       (faults),
      .frames_ok    (frames_ok),
      .crc_errors   (crc_errors),
      .length_errors(length_errors),
      .unknown_types(unknown_types),
      .noise_bytes  (noise_bytes),
      .clamped      (clamped),
      .naks         (naks),
      .limit_state  (limit_state),
      .limit_trip   (limit_trip),
      .probe_state  (probe_state)
  );

  // The status the board does not display.
  /* verilator lint_off UNUSEDSIGNAL */
  wire unused_status = &{rx_partial, running, seg_start, seg_done, position, last_period, numerator_x,
                         numerator_y, packet_count[15:8], frame_errors[15:1], timeouts[15:1],
                         overruns[15:1], violations, last_feed[15:8], fifo_level, next_seq,
                         segments_done, faults[7:1], frames_ok, crc_errors, length_errors,
                         unknown_types, noise_bytes, clamped, naks, limit_state, limit_trip,
                         probe_state};
  /* verilator lint_on UNUSEDSIGNAL */

  reg [HB_W-1:0] hb_cnt_reg;
  reg hb_reg;
  reg frame_seen_reg, drop_seen_reg;
  always @(posedge clk) begin
    if (hb_cnt_reg == HALF_SECOND[HB_W-1:0] - 1'b1) begin
      hb_cnt_reg <= {HB_W{1'b0}};
      hb_reg     <= ~hb_reg;
    end else begin
      hb_cnt_reg <= hb_cnt_reg + 1'b1;
    end
    if (frame_errors != 16'd0) frame_seen_reg <= 1'b1;
    if (timeouts != 16'd0 || overruns != 16'd0) drop_seen_reg <= 1'b1;
    if (rst) begin
      hb_cnt_reg     <= {HB_W{1'b0}};
      hb_reg         <= 1'b0;
      frame_seen_reg <= 1'b0;
      drop_seen_reg  <= 1'b0;
    end
  end

  assign step_x = step[0];
  assign dir_x  = dir[0];
  assign step_y = step[1];
  assign dir_y  = dir[1];
  assign LEDR   = {drop_seen_reg, frame_seen_reg, hb_reg, |heater_w, |faults, v2_mode, dir[1],
                   dir[0], laser, busy};

  hex7seg u_hex0 (.digit(last_feed[3:0]),    .seg_n(HEX0));
  hex7seg u_hex1 (.digit(last_feed[7:4]),    .seg_n(HEX1));
  hex7seg u_hex2 (.digit(packet_count[3:0]), .seg_n(HEX2));
  hex7seg u_hex3 (.digit(packet_count[7:4]), .seg_n(HEX3));
  hex7seg u_hex4 (.digit(busy ? 4'hB : 4'h0), .seg_n(HEX4));
  hex7seg u_hex5 (.digit({2'b00, last_code}), .seg_n(HEX5));

endmodule

`default_nettype wire
