// machine_outputs: cnc_core's laser and machine-output pins: segment_executor's levels gated by the
// motion abort, the part-cooling fan's PWM and the laser / spindle PWM (docs/architecture.md "Code
// flow in the device", step 5; docs/protocol.md "OUTPUT"; docs/machine.md "Laser and spindle PWM").
//
// Contract
//   abort        e-stop or hard-limit alarm (cnc_core's motion_abort): laser, coolant_flood,
//                coolant_mist, dout and fan are low in every clock with abort, combinationally (the
//                executor clears its own levels from the next edge).
//   exec_*       segment_executor's laser, coolant, digital-output levels and fan duty (0..255;
//                255 = always on).
//   fan          (OUTPUTS = 1) pwm with 256 counts a period at about FAN_PWM_HZ (FAN_DIV = CLK_HZ /
//                (256 * FAN_PWM_HZ), rounded; the frequency must come within 1 % of FAN_PWM_HZ). The
//                PWM takes a duty only at a period boundary: after an abort the pin stays low until
//                the first boundary (pwm's period_start), from which the duty the executor holds
//                (0 after the abort, or a later OUTPUT's) is the active one. OUTPUTS = 0: fan low,
//                exec_fan_duty not read.
//   spindle_pwm  (OUTPUTS = 1) laser_pwm with 256 counts a period at about LASER_PWM_HZ (LASER_DIV
//                as FAN_DIV), enabled by the laser pin (low in every clock the laser is low), its
//                duty from laser_scale: the running segment's power (exec_power), with exec_dyn
//                (M4, OUTPUT mask bit 7) times rate / 2^32 and, while exec_prof, exec_v / exec_vc.
//                OUTPUTS = 0: low, the exec_power .. exec_vc and rate inputs not read.
// OUTPUTS 0 or 1; FAN_PWM_HZ and LASER_PWM_HZ at least 1, at most CLK_HZ / 256 and reachable within
// 1 %. An illegal value instantiates a module named machine_outputs_illegal_<rule>, which does not
// exist.
`default_nettype none
`include "fpgacnc_spec.vh"

module machine_outputs #(
    parameter CLK_HZ     = `FPGACNC_DEF_CLK_HZ,
    parameter FAN_PWM_HZ = 1000,
    parameter LASER_PWM_HZ = `FPGACNC_DEF_LASER_PWM_HZ,
    parameter OUTPUTS    = 1
) (
    input wire clk,
    input wire rst,

    /* verilator lint_off SYMRSVDWORD */
    input wire abort,
    /* verilator lint_on SYMRSVDWORD */
    input wire       exec_laser,
    input wire       exec_flood,
    input wire       exec_mist,
    input wire [3:0] exec_dout,
    input wire [7:0] exec_fan_duty,
    input wire [ 7:0] exec_power,  // the running segment's power byte
    input wire        exec_dyn,    // M4 dynamic power (OUTPUT mask bit 7)
    input wire        exec_prof,   // the running segment is a LINE_PROFILE
    input wire [46:0] exec_v,      // its profile's V and V_cruise
    input wire [46:0] exec_vc,
    input wire [32:0] rate,        // feed_rate's rate (2^32 = 100 %)

    output wire       laser,
    output wire       coolant_flood,
    output wire       coolant_mist,
    output wire [3:0] dout,
    output wire       fan,
    output wire       spindle_pwm
);

  // fan PWM: 256 counts a period, FAN_DIV clocks a count (rounded)
  localparam integer FAN_HZ_I = (FAN_PWM_HZ < 1) ? 1 : FAN_PWM_HZ;
  localparam integer FAN_DIV_R = (CLK_HZ + 128 * FAN_HZ_I) / (256 * FAN_HZ_I);
  localparam integer FAN_DIV = (FAN_DIV_R < 1) ? 1 : FAN_DIV_R;
  localparam integer FAN_PERIOD = 256 * FAN_DIV;
  localparam integer FAN_ERR = (CLK_HZ > FAN_PERIOD * FAN_HZ_I) ? CLK_HZ - FAN_PERIOD * FAN_HZ_I
                                                                : FAN_PERIOD * FAN_HZ_I - CLK_HZ;
  localparam integer FAN_OK = (FAN_PWM_HZ >= 1 && FAN_DIV_R >= 1 &&
                               FAN_ERR <= FAN_PERIOD * FAN_HZ_I / 100) ? 1 : 0;

  // laser / spindle PWM: the same rule
  localparam integer LAS_HZ_I = (LASER_PWM_HZ < 1) ? 1 : LASER_PWM_HZ;
  localparam integer LAS_DIV_R = (CLK_HZ + 128 * LAS_HZ_I) / (256 * LAS_HZ_I);
  localparam integer LASER_DIV = (LAS_DIV_R < 1) ? 1 : LAS_DIV_R;
  localparam integer LAS_PERIOD = 256 * LASER_DIV;
  localparam integer LAS_ERR = (CLK_HZ > LAS_PERIOD * LAS_HZ_I) ? CLK_HZ - LAS_PERIOD * LAS_HZ_I
                                                                : LAS_PERIOD * LAS_HZ_I - CLK_HZ;
  localparam integer LAS_OK = (LASER_PWM_HZ >= 1 && LAS_DIV_R >= 1 &&
                               LAS_ERR <= LAS_PERIOD * LAS_HZ_I / 100) ? 1 : 0;
  localparam integer SCALE_LAT = `FPGACNC_DEF_LASER_SCALE_CLKS;  // laser_scale's (it checks it)

  generate
    if (LAS_OK == 0) begin : g_laser_bad
      machine_outputs_illegal_LASER_PWM_HZ_out_of_range u_err ();
    end
    if (OUTPUTS != 0 && OUTPUTS != 1) begin : g_bad_outputs
      machine_outputs_illegal_OUTPUTS_not_0_or_1 u_err ();
    end
    if (FAN_OK == 0) begin : g_fan_bad
      machine_outputs_illegal_FAN_PWM_HZ_out_of_range u_err ();
    end
  endgenerate

  assign laser         = exec_laser && !abort;
  assign coolant_flood = exec_flood && !abort;
  assign coolant_mist  = exec_mist && !abort;
  assign dout          = exec_dout & {4{!abort}};

  generate
    if (OUTPUTS != 0) begin : g_fan
      wire fan_pwm, fan_start;
      /* verilator lint_off UNUSEDSIGNAL */
      wire [8:0] fan_active_nc;
      /* verilator lint_on UNUSEDSIGNAL */
      reg fan_hold_reg;  // set by abort, cleared at the next period boundary
      always @(posedge clk) begin
        if (fan_start) fan_hold_reg <= 1'b0;
        if (abort) fan_hold_reg <= 1'b1;
        if (rst) fan_hold_reg <= 1'b0;
      end
      pwm #(
          .PWM_BITS(8),
          .PWM_DIV (FAN_DIV)
      ) u_fan (
          .clk         (clk),
          .rst         (rst),
          .duty        ((exec_fan_duty == 8'hFF) ? 9'd256 : {1'b0, exec_fan_duty}),
          .force_off   (abort),
          .out         (fan_pwm),
          .period_start(fan_start),
          .active      (fan_active_nc)
      );
      assign fan = fan_pwm && !abort && !(fan_hold_reg && !fan_start);
    end else begin : g_nofan
      assign fan = 1'b0;
      wire unused_fan = &{1'b0, clk, rst, exec_fan_duty};
    end
  endgenerate

  generate
    if (OUTPUTS != 0) begin : g_laser_pwm
      wire       las_sample, las_done;
      wire [7:0] las_duty;
      laser_scale #(
          .LAT(SCALE_LAT)
      ) u_laser_scale (
          .clk  (clk),
          .rst  (rst),
          .start(las_sample),
          .power(exec_power),
          .dyn  (exec_dyn),
          .prof (exec_prof),
          .rate (rate),
          .v    (exec_v),
          .vc   (exec_vc),
          .duty (las_duty),
          .done (las_done)
      );
      laser_pwm #(
          .DIV(LASER_DIV),
          .LAT(SCALE_LAT)
      ) u_laser_pwm (
          .clk   (clk),
          .rst   (rst),
          .en    (laser),
          .sample(las_sample),
          .duty  (las_duty),
          .done  (las_done),
          .out   (spindle_pwm)
      );
    end else begin : g_nolaser_pwm
      assign spindle_pwm = 1'b0;
      wire unused_laser_pwm = &{1'b0, exec_power, exec_dyn, exec_prof, exec_v, exec_vc, rate};
    end
  endgenerate

endmodule

`default_nettype wire
