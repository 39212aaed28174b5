// heater_block: the two heater channels (0 hot end, 1 bed), the shared LTC2308 master and
// thermistor tables, the sample tick and the host watchdog (docs/heater.md).
//
// Contract
//   Heater frames from frame_decoder (already checked: TYPE 0x20..0x24, LEN, fields, SEQ):
//   frame_wr (1-clock strobe), frame_type, frame_len, frame_data (payload byte i in
//   [8*i+:8], bytes 0..19). Applied at once; a THERMISTOR_TABLE writes its n entries on the n
//   clocks after the strobe (the next heater frame is at least 10 byte times away).
//   frame_ok    strobe: a frame passed every check (feeds the watchdog).
//   fault_clear strobe: clears the channel faults and the watchdog fault.
//   estop       level, synchronized and latched by the caller: both heaters low from the next
//               edge, channels disabled.
//   Sample tick: every SAMPLE_CLKS clocks: ADC read of both channels (about 620 clocks), table
//   lookups (2 x 6 clocks), then eval of both channels (controller + checks) on the same clock.
//   Watchdog: wd_period ticks (HEATER_WATCHDOG, 0 = off) without frame_ok latch wd_fault.
//   heat_status 16 bytes for STATUS: channel 0's 8 bytes first (see heater_channel), MSB first.
//   heater[1:0] pins; adc_* pins (ltc2308_spi).
//   tick: 1-clock strobe at each sample tick; sample_done: 1-clock strobe when the channels
//   evaluate this tick's temperatures.
// Latency (defaults, measured by tb/test_heater_block.cpp): tick strobe high after edge T -> the
//   channels evaluate on edge T + 635 (ADC read 619 clocks, two table lookups); a MINTEMP/MAXTEMP
//   fault is latched on that edge and the heater pin is low after edge T + 636. Watchdog and
//   e-stop: heater low after the next edge.
// rst is synchronous, active high.
`default_nettype none

module heater_block #(
    parameter SAMPLE_CLKS  = 50_000_000,  // one sample tick (1 s at 50 MHz)
    parameter PWM_BITS     = 10,
    parameter PWM_DIV      = 4883,        // PWM period PWM_DIV * 2^PWM_BITS clocks (10 Hz)
    parameter ADC_CONVST   = 4,
    parameter ADC_TCONV    = 85,
    parameter ADC_SCK_DIV  = 5,
    parameter ADC_CH0      = 0,           // LTC2308 input of the hot-end thermistor
    parameter ADC_CH1      = 1            // ... of the bed thermistor
) (
    input wire clk,
    input wire rst,

    input wire         frame_wr,
    input wire [  7:0] frame_type,
    /* verilator lint_off UNUSEDSIGNAL */
    input wire [  7:0] frame_len,  // only THERMISTOR_TABLE's (4..18) is used
    /* verilator lint_on UNUSEDSIGNAL */
    input wire [159:0] frame_data,
    input wire         frame_ok,
    input wire         fault_clear,
    input wire         estop,

    output wire [  1:0] heater,
    output wire [127:0] heat_status,
    output wire [  7:0] faults0,  // {4'b0, HEATING, RUNAWAY, MAXTEMP, MINTEMP} of channel 0
    output wire [  7:0] faults1,
    output wire         wd_fault,
    output wire         tick,
    output wire         sample_done,

    output wire adc_convst,
    output wire adc_sck,
    output wire adc_sdi,
    input  wire adc_sdo
);

  // ---------------------------------------------------------------- frame fields
  // Byte i of frame_data and the big-endian 16 / 32-bit fields at byte i. They read frame_data
  // directly rather than take it as an argument (same logic; a simulator need not copy it).
  function [7:0] fb;
    input integer i;
    begin
      fb = frame_data[8*i+:8];
    end
  endfunction
  function [15:0] f16;
    input integer i;
    begin
      f16 = {frame_data[8*i+:8], frame_data[8*(i+1)+:8]};
    end
  endfunction
  function [31:0] f32;
    input integer i;
    begin
      f32 = {frame_data[8*i+:8], frame_data[8*(i+1)+:8], frame_data[8*(i+2)+:8],
             frame_data[8*(i+3)+:8]};
    end
  endfunction

  /* verilator lint_off UNUSEDSIGNAL */
  wire [7:0] ch_byte = fb(0);  // channel (0/1: the decoder rejects others)
  wire [7:0] mode_byte = fb(1);  // mode 0..4
  wire [7:0] first_byte = fb(1);  // first table index 0..64
  /* verilator lint_on UNUSEDSIGNAL */
  wire t_cfg = frame_wr && frame_type == 8'h20;
  wire t_set = frame_wr && frame_type == 8'h21;
  wire t_tab = frame_wr && frame_type == 8'h22;
  wire t_saf = frame_wr && frame_type == 8'h23;
  wire t_wd = frame_wr && frame_type == 8'h24;

  // Channel fields of the heater frame being written: CONFIG kp, ki, kd (bytes 2, 6, 10), duty_max,
  // hyst, manual (14, 16, 18); SETPOINT value and SAFETY Tmin (1), Tmax, band, runaway period,
  // watch rise, watch period (3, 5, 7, 9, 11). Formed only in the clock of a heater frame
  // (frame_wr) and don't-care in any other: a channel takes them only with its cfg_wr, set_wr or
  // safe_wr. The same logic as the plain fields; a simulator skips it between frames.
  reg [31:0] c_kp, c_ki, c_kd;
  reg [15:0] c_umax, c_hyst, c_manual, c_b1, c_b3, c_b5, c_b7, c_b9, c_b11;
  always @(*) begin
    {c_kp, c_ki, c_kd} = {96{1'bx}};
    {c_umax, c_hyst, c_manual, c_b1, c_b3, c_b5, c_b7, c_b9, c_b11} = {144{1'bx}};
    if (frame_wr) begin
      c_kp     = f32(2);
      c_ki     = f32(6);
      c_kd     = f32(10);
      c_umax   = f16(14);
      c_hyst   = f16(16);
      c_manual = f16(18);
      c_b1     = f16(1);
      c_b3     = f16(3);
      c_b5     = f16(5);
      c_b7     = f16(7);
      c_b9     = f16(9);
      c_b11    = f16(11);
    end
  end

  // ---------------------------------------------------------------- table loader
  reg [127:0] tab_data_reg;  // entries still to write, next in [127:112]
  reg [3:0] tab_left_reg;
  reg [6:0] tab_idx_reg;
  reg tab_ch_reg;
  always @(posedge clk) begin
    if (t_tab) begin
      tab_ch_reg   <= ch_byte[0];
      tab_idx_reg  <= first_byte[6:0];
      tab_left_reg <= frame_len[4:1] - 4'd1;  // (LEN - 2) / 2 entries
      tab_data_reg <= {f16(2), f16(4), f16(6),
                       f16(8), f16(10), f16(12),
                       f16(14), f16(16)};
    end else if (tab_left_reg != 4'd0) begin
      tab_left_reg <= tab_left_reg - 4'd1;
      tab_idx_reg  <= tab_idx_reg + 7'd1;
      tab_data_reg <= {tab_data_reg[111:0], 16'd0};
    end
    if (rst) begin
      tab_left_reg <= 4'd0;
      tab_idx_reg  <= 7'd0;
      tab_ch_reg   <= 1'b0;
      tab_data_reg <= 128'd0;
    end
  end
  wire tab_wr = (tab_left_reg != 4'd0);

  // ---------------------------------------------------------------- sample tick and sequence
  localparam SW = $clog2(SAMPLE_CLKS + 1);
  localparam integer S_LAST_I = SAMPLE_CLKS - 1;
  localparam [SW-1:0] S_LAST = S_LAST_I[SW-1:0];
  reg [SW-1:0] sample_reg;
  reg tick_reg;
  localparam [2:0] Q_IDLE = 3'd0, Q_ADC = 3'd1, Q_T0 = 3'd2, Q_T1 = 3'd3;
  reg [2:0] q_reg;
  reg lk_start_reg, lk_ch_reg;
  reg [11:0] lk_code_reg;
  reg signed [15:0] t0_reg, t1_reg;
  reg eval_reg;

  wire [11:0] code_a, code_b;
  wire adc_done, lk_done;
  /* verilator lint_off UNUSEDSIGNAL */
  wire adc_busy, lk_busy;
  /* verilator lint_on UNUSEDSIGNAL */
  wire signed [15:0] lk_temp;

  always @(posedge clk) begin
    tick_reg     <= (sample_reg == S_LAST);
    sample_reg   <= (sample_reg == S_LAST) ? {SW{1'b0}} : sample_reg + 1'b1;
    lk_start_reg <= 1'b0;
    eval_reg     <= 1'b0;
    case (q_reg)
      Q_IDLE: if (tick_reg) q_reg <= Q_ADC;
      Q_ADC:
      if (adc_done) begin
        lk_start_reg <= 1'b1;
        lk_ch_reg    <= 1'b0;
        lk_code_reg  <= code_a;
        q_reg        <= Q_T0;
      end
      Q_T0:
      if (lk_done) begin
        t0_reg       <= lk_temp;
        lk_start_reg <= 1'b1;
        lk_ch_reg    <= 1'b1;
        lk_code_reg  <= code_b;
        q_reg        <= Q_T1;
      end
      Q_T1:
      if (lk_done) begin
        t1_reg   <= lk_temp;
        eval_reg <= 1'b1;
        q_reg    <= Q_IDLE;
      end
      default: q_reg <= Q_IDLE;
    endcase
    if (rst) begin
      sample_reg   <= {SW{1'b0}};
      tick_reg     <= 1'b0;
      q_reg        <= Q_IDLE;
      lk_start_reg <= 1'b0;
      lk_ch_reg    <= 1'b0;
      lk_code_reg  <= 12'd0;
      t0_reg       <= 16'sd0;
      t1_reg       <= 16'sd0;
      eval_reg     <= 1'b0;
    end
  end

  ltc2308_spi #(
      .CONVST_CLKS(ADC_CONVST),
      .TCONV_CLKS (ADC_TCONV),
      .SCK_DIV    (ADC_SCK_DIV),
      .CH_A       (ADC_CH0),
      .CH_B       (ADC_CH1)
  ) u_adc (
      .clk       (clk),
      .rst       (rst),
      .start     (tick_reg && q_reg == Q_IDLE),
      .code_a    (code_a),
      .code_b    (code_b),
      .done      (adc_done),
      .busy      (adc_busy),
      .adc_convst(adc_convst),
      .adc_sck   (adc_sck),
      .adc_sdi   (adc_sdi),
      .adc_sdo   (adc_sdo)
  );

  temp_table u_table (
      .clk    (clk),
      .rst    (rst),
      .wr     (tab_wr),
      .wr_ch  (tab_ch_reg),
      .wr_idx (tab_idx_reg),
      .wr_data(tab_data_reg[127:112]),
      .start  (lk_start_reg),
      .ch     (lk_ch_reg),
      .code   (lk_code_reg),
      .temp   (lk_temp),
      .done   (lk_done),
      .busy   (lk_busy)
  );

  // ---------------------------------------------------------------- watchdog
  reg [15:0] wd_period_reg, wd_count_reg;
  reg wd_fault_reg;
  always @(posedge clk) begin
    if (t_wd) wd_period_reg <= f16(0);
    if (frame_ok || t_wd) wd_count_reg <= 16'd0;
    else if (tick_reg && wd_period_reg != 16'd0 && wd_count_reg != 16'hFFFF)
      wd_count_reg <= wd_count_reg + 16'd1;
    if (fault_clear) wd_fault_reg <= 1'b0;
    if (wd_period_reg != 16'd0 && wd_count_reg >= wd_period_reg && !frame_ok && !t_wd)
      wd_fault_reg <= 1'b1;
    if (rst) begin
      wd_period_reg <= 16'd0;
      wd_count_reg  <= 16'd0;
      wd_fault_reg  <= 1'b0;
    end
  end

  // ---------------------------------------------------------------- channels
  wire kill = estop || wd_fault_reg;
  wire [3:0] f0, f1;
  wire [63:0] st0, st1;
  /* verilator lint_off UNUSEDSIGNAL */
  wire [PWM_BITS:0] duty0, duty1;
  wire pd0, pd1, en0, en1;
  /* verilator lint_on UNUSEDSIGNAL */

  heater_channel #(
      .PWM_BITS   (PWM_BITS),
      .PWM_DIV    (PWM_DIV),
      .DEF_TMIN   (16'sd80),
      .DEF_TMAX   (16'sd4400),
      .DEF_BAND   (16'd64),
      .DEF_RPERIOD(16'd40),
      .DEF_WRISE  (16'd32),
      .DEF_WPERIOD(16'd20)
  ) u_ch0 (
      .clk         (clk),
      .rst         (rst),
      .cfg_wr      (t_cfg && ch_byte[0] == 1'b0),
      .cfg_mode    (mode_byte[2:0]),
      .cfg_kp      (c_kp),
      .cfg_ki      (c_ki),
      .cfg_kd      (c_kd),
      .cfg_umax    (c_umax),
      .cfg_hyst    (c_hyst),
      .cfg_manual  (c_manual),
      .set_wr      (t_set && ch_byte[0] == 1'b0),
      .set_value   (c_b1),
      .safe_wr     (t_saf && ch_byte[0] == 1'b0),
      .safe_tmin   (c_b1),
      .safe_tmax   (c_b3),
      .safe_band   (c_b5),
      .safe_rperiod(c_b7),
      .safe_wrise  (c_b9),
      .safe_wperiod(c_b11),
      .eval        (eval_reg),
      .temp        (t0_reg),
      .kill        (kill),
      .fault_clear (fault_clear),
      .heater      (heater[0]),
      .status      (st0),
      .faults      (f0),
      .duty        (duty0),
      .pid_done    (pd0),
      .enabled     (en0)
  );

  heater_channel #(
      .PWM_BITS   (PWM_BITS),
      .PWM_DIV    (PWM_DIV),
      .DEF_TMIN   (16'sd80),
      .DEF_TMAX   (16'sd1920),  // 120 degC
      .DEF_BAND   (16'd64),
      .DEF_RPERIOD(16'd40),
      .DEF_WRISE  (16'd32),
      .DEF_WPERIOD(16'd60)
  ) u_ch1 (
      .clk         (clk),
      .rst         (rst),
      .cfg_wr      (t_cfg && ch_byte[0] == 1'b1),
      .cfg_mode    (mode_byte[2:0]),
      .cfg_kp      (c_kp),
      .cfg_ki      (c_ki),
      .cfg_kd      (c_kd),
      .cfg_umax    (c_umax),
      .cfg_hyst    (c_hyst),
      .cfg_manual  (c_manual),
      .set_wr      (t_set && ch_byte[0] == 1'b1),
      .set_value   (c_b1),
      .safe_wr     (t_saf && ch_byte[0] == 1'b1),
      .safe_tmin   (c_b1),
      .safe_tmax   (c_b3),
      .safe_band   (c_b5),
      .safe_rperiod(c_b7),
      .safe_wrise  (c_b9),
      .safe_wperiod(c_b11),
      .eval        (eval_reg),
      .temp        (t1_reg),
      .kill        (kill),
      .fault_clear (fault_clear),
      .heater      (heater[1]),
      .status      (st1),
      .faults      (f1),
      .duty        (duty1),
      .pid_done    (pd1),
      .enabled     (en1)
  );

  assign heat_status = {st0, st1};
  assign faults0     = {4'd0, f0};
  assign faults1     = {4'd0, f1};
  assign wd_fault    = wd_fault_reg;
  assign tick        = tick_reg;
  assign sample_done = eval_reg;

endmodule

`default_nettype wire
