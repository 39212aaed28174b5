// cnc_core: the board-independent controller, protocols v1 and v2: the wiring of the blocks in
// docs/architecture.md ("Code flow in the device"): uart_rx, the front end (front_v2: decoder and
// command FIFO, or front_v1: the v1 decoder), step_config, segment_prep, segment_executor,
// machine_outputs, estop_latch, the hard limits (input_filter, limit_guard), heater_block,
// status_counters, answer_source, uart_tx.
//
// Contract
//   rx / tx          the UART (BAUD, 8N1); the protocol is docs/protocol.md.
//   step, dir, laser the motion pins (docs/timing.md); coolant_flood, coolant_mist, fan (PWM at
//                    about FAN_PWM_HZ), dout: machine outputs set by OUTPUT entries on the edge
//                    that ends the segment before them; low after rst and on e-stop.
//   spindle_pwm      (OUTPUTS) laser power / spindle speed: PWM at about LASER_PWM_HZ while
//                    `laser` is high (low whenever it is low), duty = the segment's power byte;
//                    with OUTPUT mask bit 7 set to 1 (M4) scaled by the actual speed over the
//                    programmed one (docs/machine.md "Laser and spindle PWM").
//   heater, adc_*    the two heater channels and the LTC2308 (docs/heater.md; SAMPLE_CLKS clocks a
//                    sample tick).
//   estop            active high, asynchronous (the board top inverts its estop_n pin): two-flop
//                    synchronizer, latched (faults bit 4) until a FAULT_CLEAR while released. While
//                    active or latched: FIFO held flushed, segment_prep and segment_executor
//                    aborted (no new STEP rise; positions and v1 numerators kept), laser and
//                    outputs low (2 clocks from the pin), heaters low (3 clocks).
//   limit_min, limit_max   per-axis limit switches, asynchronous (docs/machine.md): input_filter
//                    (LIMIT_ACTIVE_LOW, LIMIT_FILTER_CLKS; a switch not in LIMIT_ENABLE reads
//                    released), then limit_guard: a switch rising while the executor is busy, or
//                    a step request toward an asserted switch, trips the alarm (faults bit 2,
//                    limit_trip): that step is not issued, no STEP rises from the clock after
//                    the trip, and as for the e-stop the FIFO is flushed, prep and executor
//                    aborted (positions kept), laser and outputs low; heaters keep running. The
//                    alarm clears on a FAULT_CLEAR while the switch that tripped is released;
//                    STATUS state bit 4 (positions not trusted) stays set until rst.
//   soft limits      (v2) CONFIG_TRAVEL sets an axis's travel in steps (off after rst); a LINE,
//                    LINE_PROFILE or ARC whose end leaves it is answered NAK TRAVEL and not queued
//                    (frame_decoder's travel_guard); its queued end position resyncs to the
//                    position counters while the FIFO is held flushed (e-stop, hard limit).
//   feed hold        (v2) rtl/motion/feed_rate.v (docs/timing.md "Feed hold and overrides"): a
//                    MOTION frame sets the feed and rapid rates (<= 100 %) and the ramp, and holds,
//                    resumes or cancels; hold_in / start_in (BUTTON_* parameters, filtered like the
//                    limit switches) request a hold / a resume on the filtered level's rise. Every
//                    motion generator advances only in the clocks feed_rate enables, so the path
//                    is the planned one at any rate; the laser is low while the rate is 0. A
//                    CANCEL holds and, at rest, flushes as the e-stop does (positions kept, no
//                    fault). STATUS state bits 5 HOLD and 6 STOPPED.
//   homing, probing  (v2, TRIGGER) rtl/machine/trigger_latch.v (docs/machine.md "Homing and
//                    probing (hardware)"): probe_in passes its own input_filter (PROBE_ENABLE,
//                    PROBE_ACTIVE_LOW, PROBE_FILTER_CLKS; STATUS state bit 7 PROBE, probe_state).
//                    A TRIGGER frame arms HOME (a mask of switches: their hard-limit trips are
//                    suppressed, their step block stays; each switch's filtered rise latches its
//                    axis's position; when all have fired, motion_abort for one clock: FIFO, prep
//                    and executor dropped, no fault, positions kept) or PROBE (the filtered probe's
//                    edge to the level latches every position and starts feed_rate's CANCEL).
//                    TRIGGER_QUERY is answered by TRIGGER_REPORT. SET_POSITION (only while quiet,
//                    else NAK BUSY) sets the chosen axes' positions (rtl/machine/position_offset.v:
//                    `position` = the executor's STEP counters + an offset per axis, from the
//                    next clock), resyncs travel_guard's queued end on the clock after and clears
//                    state bit 4 (positions not trusted).
//   cfg_wr, cfg_addr, cfg_wdata   step timing write port, address axis * 4 + field (0 STEP
//                    high, 1 STEP low, 2 DIR setup, 3 DIR hold, clocks). Like CONFIG_AXIS frames it
//                    writes a shadow set that becomes active only while the FIFO is empty and
//                    nothing is prepared or running; the port wins over a frame on the same clock
//                    and field.
//   status outputs   registers; the 16-bit counters wrap. STATUS carries frames_ok, crc_errors,
//                    length_errors, unknown_types, timeouts, frame_errors, overruns, noise_bytes,
//                    clamped (docs/protocol.md "STATUS"); packet_count, violations and naks are
//                    pins only. faults: bit 0 STEP timing violation, 1 arc error, 2 hard limit,
//                    4 e-stop, 5..7 heaters; latched until FAULT_CLEAR.
//   rst              synchronous, active high (the board top synchronizes its button).
// Build options (docs/synthesis.md "Build options"; named configurations in spec/configs.toml):
//   PROTO_V2 = 0 is the original v1 controller (packet_decoder_v1, no FIFO, no response_encoder,
//   faults clear only at rst) and implies PROFILES = ARCS = HEATERS = OUTPUTS = 0; with PROTO_V2 =
//   1 each of PROFILES, ARCS, HEATERS, OUTPUTS, TRIGGER = 0 removes its block and answers its frames
//   NAK UNKNOWN_TYPE (TRIGGER: TRIGGER, SET_POSITION, TRIGGER_QUERY; probe_in unused). LEAN_TRIM = 1 and STEP_CFG = 0 (PROTO_V2 = 0 only) trim the v1 datapath and fix
//   the step timing at its parameters, with the same pins on every clock. N_AXES 2..15. An illegal
//   combination stops elaboration (a module named cnc_core_illegal_<rule> is instantiated, which
//   does not exist).
`default_nettype none
`include "fpgacnc_spec.vh"

module cnc_core #(
    parameter CLK_HZ            = `FPGACNC_DEF_CLK_HZ,
    parameter BAUD              = `FPGACNC_DEF_BAUD,
    parameter N_AXES            = `FPGACNC_DEF_N_AXES,
    parameter WATCHDOG_CLKS     = CLK_HZ / 10,         // 100 ms packet watchdog
    parameter FEED0_PERIOD      = `FPGACNC_DEF_FEED0_PERIOD,  // dominant period when feed = 0
    // CLK_HZ * 60 / steps per mm
    parameter DEFAULT_NUMERATOR = CLK_HZ / `FPGACNC_DEF_STEPS_PER_MM * 60,
    parameter STEP_HIGH         = `FPGACNC_DEF_STEP_HIGH,
    parameter STEP_LOW          = `FPGACNC_DEF_STEP_LOW,
    parameter DIR_SETUP         = `FPGACNC_DEF_DIR_SETUP,
    parameter DIR_HOLD          = `FPGACNC_DEF_DIR_HOLD,
    parameter FIFO_DEPTH        = `FPGACNC_DEF_FIFO_DEPTH,  // command FIFO entries (power of two)
    parameter BUILD_ID          = `FPGACNC_BUILD_ID,   // reported by IDENT
    parameter SAMPLE_CLKS       = CLK_HZ,              // heater sample tick (1 s)
    parameter HEAT_PWM_BITS     = 10,
    parameter HEAT_PWM_DIV      = 4883,                // heater PWM 10 Hz at 50 MHz
    parameter PROTO_V2          = 1,                   // build options (header comment)
    parameter PROFILES          = PROTO_V2,
    parameter ARCS              = PROTO_V2,
    parameter HEATERS           = PROTO_V2,
    parameter OUTPUTS           = PROTO_V2,
    parameter FAN_PWM_HZ        = 1000,                // fan PWM frequency (256 counts a period)
    parameter LASER_PWM_HZ      = `FPGACNC_DEF_LASER_PWM_HZ,  // spindle_pwm frequency (256 counts)
    parameter LEAN_TRIM         = (PROTO_V2 == 0) ? 1 : 0,  // 1: PROTO_V2 = 0 only
    parameter STEP_CFG          = 1,                   // 0: PROTO_V2 = 0 only
    // hard limits (docs/machine.md): bit a = min switch of axis a, bit 16 + a = max switch
    parameter LIMIT_FILTER_CLKS = `FPGACNC_DEF_LIMIT_FILTER_CLKS,  // debounce, clocks
    parameter [31:0] LIMIT_ENABLE     = `FPGACNC_DEF_LIMIT_ENABLE,      // switches wired
    parameter [31:0] LIMIT_ACTIVE_LOW = `FPGACNC_DEF_LIMIT_ACTIVE_LOW,  // asserted at a low pin
    // feed hold and cycle-start buttons (docs/machine.md): bit 0 hold, bit 1 cycle start
    parameter [1:0] BUTTON_ENABLE     = 2'b11,  // buttons wired (a button not wired reads released)
    parameter [1:0] BUTTON_ACTIVE_LOW = 2'b00,  // asserted at a low pin
    parameter RATE_PERIOD_LOG2        = `FPGACNC_DEF_RATE_PERIOD_LOG2,  // motion rate period
    parameter [31:0] RATE_RAMP        = `FPGACNC_DEF_RATE_RAMP,  // motion rate ramp after rst
    // homing and probing trigger (docs/machine.md "Homing and probing (hardware)"), v2 only
    parameter TRIGGER                 = PROTO_V2,  // 1: PROTO_V2 = 1 only
    parameter PROBE_FILTER_CLKS       = `FPGACNC_DEF_PROBE_FILTER_CLKS,  // probe debounce, clocks
    parameter PROBE_ENABLE            = `FPGACNC_DEF_PROBE_ENABLE,  // probe wired (else released)
    parameter PROBE_ACTIVE_LOW        = `FPGACNC_DEF_PROBE_ACTIVE_LOW  // asserted at a low pin
) (
    input wire clk,
    input wire rst,

    input  wire rx,
    output wire tx,

    output wire [N_AXES-1:0] step,
    output wire [N_AXES-1:0] dir,
    output wire              laser,

    output wire       coolant_flood,  // machine outputs (OUTPUT frames)
    output wire       coolant_mist,
    output wire       fan,            // part-cooling fan PWM
    output wire [3:0] dout,           // digital outputs (M62..M65 P0..P3)
    output wire       spindle_pwm,    // laser power / spindle speed PWM (M3 / M4 S)

    input  wire       estop,       // e-stop, active high, asynchronous
    input  wire [N_AXES-1:0] limit_min,  // limit switches, asynchronous (LIMIT_* parameters)
    input  wire [N_AXES-1:0] limit_max,
    input  wire       hold_in,     // feed hold button, asynchronous (BUTTON_* parameters)
    input  wire       start_in,    // cycle start (resume) button, asynchronous
    input  wire       probe_in,    // probe, asynchronous (PROBE_* parameters)
    output wire [1:0] heater,      // 0 hot end, 1 bed
    output wire       adc_convst,  // LTC2308
    output wire       adc_sck,
    output wire       adc_sdi,
    input  wire       adc_sdo,

    input wire        cfg_wr,
    input wire [ 7:0] cfg_addr,
    input wire [15:0] cfg_wdata,

    output wire                 busy,        // an entry is queued, or a move prepared or running
    output wire                 running,     // the DDA is ticking
    output wire                 seg_start,   // high during the first tick of a move
    output wire                 seg_done,    // 1-clock strobe when a move completes
    output wire [32*N_AXES-1:0] position,
    output wire [         1:0] last_code,
    output wire [        15:0] last_feed,
    output wire [        31:0] last_period,  // dominant step period of the last move, clocks
    output wire [        15:0] packet_count,
    output wire [        15:0] frame_errors,
    output wire [        15:0] timeouts,
    output wire [        15:0] overruns,
    output wire [        15:0] violations,
    output wire [        31:0] numerator_x,
    output wire [        31:0] numerator_y,

    output wire [        15:0] fifo_level,     // entries in the command FIFO
    output wire [         7:0] next_seq,       // v2 sequence number expected next
    output wire                v2_mode,        // the decoder accepts only v2 frames
    output wire                rx_partial,     // the decoder holds a started, incomplete packet/frame
    output wire [        31:0] segments_done,  // completed v2 FIFO entries
    output wire [         7:0] faults,         // latched faults (docs/protocol.md STATUS byte 1)
    output wire [        15:0] frames_ok,
    output wire [        15:0] crc_errors,
    output wire [        15:0] length_errors,
    output wire [        15:0] unknown_types,
    output wire [        15:0] noise_bytes,
    output wire [        15:0] clamped,        // v2 segments whose T was raised
    output wire [        15:0] naks,           // NAK frames requested
    output wire [2*N_AXES-1:0] limit_state,    // filtered switches {max, min}, 1 = asserted
    output wire                limit_trip,     // the hard-limit alarm (faults bit 2)
    output wire                probe_state     // the filtered probe, 1 = asserted (STATUS bit 7)
);

  // FIFO entry (segment_prep header, LINE_PROFILE and ARC fields): 839 bits for 4 axes
  localparam ENTRY_W = `FPGACNC_ENTRY_W + 32 * N_AXES;
  // build options in effect (v1 carries no profiles, arcs or heater frames)
  localparam integer V2_EN = (PROTO_V2 != 0) ? 1 : 0;
  localparam integer PROF_EN = (V2_EN != 0 && PROFILES != 0) ? 1 : 0;
  localparam integer ARC_EN = (V2_EN != 0 && ARCS != 0) ? 1 : 0;
  localparam integer HEAT_EN = (V2_EN != 0 && HEATERS != 0) ? 1 : 0;
  localparam integer OUT_EN = (V2_EN != 0 && OUTPUTS != 0) ? 1 : 0;
  localparam integer TRIG_EN = (V2_EN != 0 && TRIGGER != 0) ? 1 : 0;
  // v1-only datapath trims (segment_prep V1_ONLY, executor LEAN_DDA)
  localparam integer TRIM_EN = (V2_EN == 0 && LEAN_TRIM != 0) ? 1 : 0;
  // v1 build with the step timing fixed at STEP_HIGH / STEP_LOW / DIR_SETUP / DIR_HOLD
  localparam integer FIXED_EN = (V2_EN == 0 && STEP_CFG == 0) ? 1 : 0;

  // ---------------------------------------------------------------- build option guards
  // An illegal combination of the build options (header comment) instantiates a module that does
  // not exist, named after the rule it breaks: Verilator, Icarus, Yosys and Quartus all stop at
  // elaboration and name it.
  generate
    if (PROTO_V2 != 0 && PROTO_V2 != 1) begin : g_bad_proto_v2
      cnc_core_illegal_PROTO_V2_not_0_or_1 u_err ();
    end
    if (PROFILES != 0 && PROFILES != 1) begin : g_bad_profiles
      cnc_core_illegal_PROFILES_not_0_or_1 u_err ();
    end
    if (ARCS != 0 && ARCS != 1) begin : g_bad_arcs
      cnc_core_illegal_ARCS_not_0_or_1 u_err ();
    end
    if (HEATERS != 0 && HEATERS != 1) begin : g_bad_heaters
      cnc_core_illegal_HEATERS_not_0_or_1 u_err ();
    end
    if (OUTPUTS != 0 && OUTPUTS != 1) begin : g_bad_outputs
      cnc_core_illegal_OUTPUTS_not_0_or_1 u_err ();
    end
    if (LEAN_TRIM != 0 && LEAN_TRIM != 1) begin : g_bad_lean_trim
      cnc_core_illegal_LEAN_TRIM_not_0_or_1 u_err ();
    end
    if (STEP_CFG != 0 && STEP_CFG != 1) begin : g_bad_step_cfg
      cnc_core_illegal_STEP_CFG_not_0_or_1 u_err ();
    end
    if (N_AXES < 2 || N_AXES > 15) begin : g_bad_n_axes
      cnc_core_illegal_N_AXES_not_2_to_15 u_err ();
    end
    // v1 carries no profile, arc, heater or OUTPUT frame
    if (PROTO_V2 == 0 && PROFILES != 0) begin : g_v1_profiles
      cnc_core_illegal_PROFILES_needs_PROTO_V2_1 u_err ();
    end
    if (PROTO_V2 == 0 && ARCS != 0) begin : g_v1_arcs
      cnc_core_illegal_ARCS_needs_PROTO_V2_1 u_err ();
    end
    if (PROTO_V2 == 0 && HEATERS != 0) begin : g_v1_heaters
      cnc_core_illegal_HEATERS_needs_PROTO_V2_1 u_err ();
    end
    if (PROTO_V2 == 0 && OUTPUTS != 0) begin : g_v1_outputs
      cnc_core_illegal_OUTPUTS_needs_PROTO_V2_1 u_err ();
    end
    // the v1 datapath trims and the fixed step timing exist in the v1 build only
    if (PROTO_V2 != 0 && LEAN_TRIM != 0) begin : g_v2_lean_trim
      cnc_core_illegal_LEAN_TRIM_needs_PROTO_V2_0 u_err ();
    end
    if (PROTO_V2 != 0 && STEP_CFG == 0) begin : g_v2_step_cfg
      cnc_core_illegal_STEP_CFG_0_needs_PROTO_V2_0 u_err ();
    end
    if (TRIGGER != 0 && TRIGGER != 1) begin : g_bad_trigger
      cnc_core_illegal_TRIGGER_not_0_or_1 u_err ();
    end
    if (PROTO_V2 == 0 && TRIGGER != 0) begin : g_v1_trigger
      cnc_core_illegal_TRIGGER_needs_PROTO_V2_1 u_err ();
    end
    if (PROBE_ENABLE != 0 && PROBE_ENABLE != 1) begin : g_bad_probe_enable
      cnc_core_illegal_PROBE_ENABLE_not_0_or_1 u_err ();
    end
    if (PROBE_ACTIVE_LOW != 0 && PROBE_ACTIVE_LOW != 1) begin : g_bad_probe_active_low
      cnc_core_illegal_PROBE_ACTIVE_LOW_not_0_or_1 u_err ();
    end
    if (PROBE_FILTER_CLKS < 0 || PROBE_FILTER_CLKS > 16777215) begin : g_bad_probe_filter
      cnc_core_illegal_PROBE_FILTER_CLKS_not_0_to_2p24m1 u_err ();
    end
    if (LIMIT_FILTER_CLKS < 0 || LIMIT_FILTER_CLKS > 16777215) begin : g_bad_limit_filter
      cnc_core_illegal_LIMIT_FILTER_CLKS_not_0_to_2p24m1 u_err ();
    end
  endgenerate

  // ---------------------------------------------------------------- UART in
  wire [7:0] rx_tdata;
  wire rx_tvalid, rx_tready, rx_frame_error, rx_overrun;
  /* verilator lint_off UNUSEDSIGNAL */
  wire rx_busy, tx_busy;  // not needed here
  /* verilator lint_on UNUSEDSIGNAL */

  uart_rx #(
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD)
  ) u_rx (
      .clk          (clk),
      .rst          (rst),
      .rxd          (rx),
      .m_axis_tdata (rx_tdata),
      .m_axis_tvalid(rx_tvalid),
      .m_axis_tready(rx_tready),
      .busy         (rx_busy),
      .frame_error  (rx_frame_error),
      .overrun_error(rx_overrun)
  );

  // ---------------------------------------------------------------- front end
  // Common to both protocol builds: the decoder's configuration, heater and fault-clear requests,
  // its status strobes, and the entry stream into segment_prep (cmd_*).
  wire dec_cfg_wr;
  wire [7:0] dec_cfg_axis;
  wire [63:0] dec_cfg_data;
  wire dec_heat_wr;
  wire [7:0] dec_heat_type, dec_heat_len;
  wire [159:0] dec_heat_data;
  wire dec_fault_clear, dec_nak;
  wire [7:0] dec_next_seq;
  wire dec_v2_mode, dec_frame_ok, dec_crc_error, dec_length_error, dec_unknown_type;
  wire dec_timeout, dec_noise, dec_v1_packet, dec_v1_overrun;
  wire [ENTRY_W-1:0] cmd_tdata;
  wire cmd_tvalid, cmd_tready;
  wire [15:0] fifo_level_w, fifo_free_w;
  wire dec_hello, dec_status, dec_ack;  // requests to response_encoder (v2 only)
  wire dec_motion_set;  // an accepted MOTION frame (v2 only), its payload in dec_motion_data
  wire [71:0] dec_motion_data;
  wire [7:0] dec_nak_seq, dec_nak_reason;
  wire estop_stop;  // e-stop active or latched (below)
  // e-stop, hard-limit alarm or a MOTION CANCEL at rest: FIFO flushed, prep and executor aborted
  wire motion_abort;
  // TRIGGER, SET_POSITION, TRIGGER_QUERY (v2 with TRIGGER), their payload
  wire dec_trig_wr, dec_setpos_wr, dec_trig_query;
  wire [8*(2+4*N_AXES)-1:0] dec_ctl_data;
  wire quiet;  // FIFO empty, nothing prepared or running
  wire [2*N_AXES-1:0] trig_suppress;  // trigger_latch: switches whose trips are suppressed
  wire trig_flush, trig_cancel, probe_lvl;
  wire [32*N_AXES-1:0] exec_position;  // the executor's STEP counters (position: + SET_POSITION's offset)
  reg setpos_q_reg;  // a SET_POSITION wrote the position counters on the last edge

  generate
    if (V2_EN != 0) begin : g_v2
      front_v2 #(
          .N_AXES       (N_AXES),
          .WATCHDOG_CLKS(WATCHDOG_CLKS),
          .FIFO_DEPTH   (FIFO_DEPTH),
          .PROFILES     (PROF_EN),
          .ARCS         (ARC_EN),
          .OUTPUTS      (OUT_EN),
          .HEATERS      (HEAT_EN),
          .TRIGGER      (TRIG_EN)
      ) u_front (
          .clk          (clk),
          .rst          (rst),
          .s_axis_tdata (rx_tdata),
          .s_axis_tvalid(rx_tvalid),
          .s_axis_tready(rx_tready),
          .m_axis_tdata (cmd_tdata),
          .m_axis_tvalid(cmd_tvalid),
          .m_axis_tready(cmd_tready),
          .flush        (motion_abort),
          .resync       (setpos_q_reg),
          .position     (position),
          .level        (fifo_level_w),
          .free         (fifo_free_w),
          .cfg_wr       (dec_cfg_wr),
          .cfg_axis     (dec_cfg_axis),
          .cfg_data     (dec_cfg_data),
          .heat_wr      (dec_heat_wr),
          .heat_type    (dec_heat_type),
          .heat_len     (dec_heat_len),
          .heat_data    (dec_heat_data),
          .fault_clear  (dec_fault_clear),
          .hello        (dec_hello),
          .status_req   (dec_status),
          .motion_set   (dec_motion_set),
          .motion_data  (dec_motion_data),
          .trig_wr      (dec_trig_wr),
          .setpos_wr    (dec_setpos_wr),
          .trig_query   (dec_trig_query),
          .ctl_data     (dec_ctl_data),
          .motion_quiet (quiet),
          .ack_req      (dec_ack),
          .nak          (dec_nak),
          .nak_seq      (dec_nak_seq),
          .nak_reason   (dec_nak_reason),
          .next_seq     (dec_next_seq),
          .v2_mode      (dec_v2_mode),
          .partial      (rx_partial),
          .frame_ok     (dec_frame_ok),
          .crc_error    (dec_crc_error),
          .length_error (dec_length_error),
          .unknown_type (dec_unknown_type),
          .timeout      (dec_timeout),
          .noise        (dec_noise),
          .v1_packet    (dec_v1_packet),
          .v1_overrun   (dec_v1_overrun)
      );
    end else begin : g_v1
      front_v1 #(
          .N_AXES       (N_AXES),
          .WATCHDOG_CLKS(WATCHDOG_CLKS)
      ) u_front (
          .clk          (clk),
          .rst          (rst),
          .s_axis_tdata (rx_tdata),
          .s_axis_tvalid(rx_tvalid),
          .s_axis_tready(rx_tready),
          .m_axis_tdata (cmd_tdata),
          .m_axis_tvalid(cmd_tvalid),
          .m_axis_tready(cmd_tready),
          .level        (fifo_level_w),
          .free         (fifo_free_w),
          .timeout      (dec_timeout),
          .overrun      (dec_v1_overrun),
          .packet_done  (dec_v1_packet),
          .partial      (rx_partial)
      );
      // no v2 frames: no configuration, heater, fault-clear or answer requests, no v2 status
      assign dec_hello        = 1'b0;
      assign dec_status       = 1'b0;
      assign dec_motion_set   = 1'b0;
      assign dec_motion_data  = 72'd0;
      assign dec_trig_wr      = 1'b0;
      assign dec_setpos_wr    = 1'b0;
      assign dec_trig_query   = 1'b0;
      assign dec_ctl_data     = {8 * (2 + 4 * N_AXES) {1'b0}};
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_setpos = &{1'b0, setpos_q_reg};  // no SET_POSITION in v1
      /* verilator lint_on UNUSEDSIGNAL */
      assign dec_ack          = 1'b0;
      assign dec_nak_seq      = 8'd0;
      assign dec_nak_reason   = 8'd0;
      assign dec_cfg_wr       = 1'b0;
      assign dec_cfg_axis     = 8'd0;
      assign dec_cfg_data     = 64'd0;
      assign dec_heat_wr      = 1'b0;
      assign dec_heat_type    = 8'd0;
      assign dec_heat_len     = 8'd0;
      assign dec_heat_data    = 160'd0;
      assign dec_fault_clear  = 1'b0;
      assign dec_nak          = 1'b0;
      assign dec_next_seq     = 8'd0;
      assign dec_v2_mode      = 1'b0;
      assign dec_frame_ok     = 1'b0;
      assign dec_crc_error    = 1'b0;
      assign dec_length_error = 1'b0;
      assign dec_unknown_type = 1'b0;
      assign dec_noise        = 1'b0;
    end
  endgenerate

  // ---------------------------------------------------------------- e-stop
  wire estop_active, estop_latched;
  estop_latch u_estop (
      .clk        (clk),
      .rst        (rst),
      .estop      (estop),
      .fault_clear(dec_fault_clear),
      .active     (estop_active),
      .latched    (estop_latched),
      .stop       (estop_stop)
  );

  // ---------------------------------------------------------------- hard limits
  localparam [N_AXES-1:0] LIM_EN_MIN = LIMIT_ENABLE[N_AXES-1:0];
  localparam [N_AXES-1:0] LIM_EN_MAX = LIMIT_ENABLE[16+N_AXES-1:16];
  localparam [N_AXES-1:0] LIM_LOW_MIN = LIMIT_ACTIVE_LOW[N_AXES-1:0];
  localparam [N_AXES-1:0] LIM_LOW_MAX = LIMIT_ACTIVE_LOW[16+N_AXES-1:16];
  wire [2*N_AXES-1:0] lim_q, lim_strobe;
  wire [N_AXES-1:0] lim_min_w = lim_q[N_AXES-1:0] & LIM_EN_MIN;
  wire [N_AXES-1:0] lim_max_w = lim_q[2*N_AXES-1:N_AXES] & LIM_EN_MAX;
  wire [N_AXES-1:0] exec_step_want, exec_step_block;
  wire limit_trip_w, limit_untrusted, limit_trip_max;
  wire [3:0] limit_trip_axis;

  input_filter #(
      .N          (2 * N_AXES),
      .FILTER_CLKS(LIMIT_FILTER_CLKS),
      .ACTIVE_LOW ({LIM_LOW_MAX, LIM_LOW_MIN})
  ) u_limit_filter (
      .clk   (clk),
      .rst   (rst),
      .din   ({limit_max, limit_min}),
      .q     (lim_q),
      .strobe(lim_strobe)
  );

  limit_guard #(
      .N_AXES(N_AXES)
  ) u_limit_guard (
      .clk      (clk),
      .rst      (rst),
      .lim_min  (lim_min_w),
      .lim_max  (lim_max_w),
      .rise_min (lim_strobe[N_AXES-1:0] & lim_min_w),
      .rise_max (lim_strobe[2*N_AXES-1:N_AXES] & lim_max_w),
      .step_want(exec_step_want),
      .dir      (dir),
      .busy     (exec_busy),
      .clear    (dec_fault_clear),
      .sup_min  (trig_suppress[N_AXES-1:0]),
      .sup_max  (trig_suppress[2*N_AXES-1:N_AXES]),
      .trust    (dec_setpos_wr),
      .block    (exec_step_block),
      .trip     (limit_trip_w),
      .trip_axis(limit_trip_axis),
      .trip_max (limit_trip_max),
      .untrusted(limit_untrusted)
  );
  assign limit_state = {lim_max_w, lim_min_w};
  assign limit_trip  = limit_trip_w;

  // ---------------------------------------------------------------- homing and probing
  // the probe through its own filter, trigger_latch (TRIGGER frames), SET_POSITION's write of the
  // position counters (docs/machine.md "Homing and probing (hardware)")
  wire [31:0] trig_state;  // TRIGGER_REPORT bytes 0..3: mode, flags, fired u16
  wire [32*N_AXES-1:0] trig_pos;
  wire [N_AXES-1:0] setpos_wr;
  wire [32*N_AXES-1:0] setpos_data;
  /* verilator lint_off UNUSEDSIGNAL */
  wire [15:0] setpos_mask16 = {dec_ctl_data[7:0], dec_ctl_data[15:8]};  // bits < N_AXES used
  /* verilator lint_on UNUSEDSIGNAL */

  genvar ga;
  generate
    for (ga = 0; ga < N_AXES; ga = ga + 1) begin : g_setpos
      assign setpos_wr[ga] = dec_setpos_wr && setpos_mask16[ga];
      assign setpos_data[32*ga+:32] = {dec_ctl_data[8*(2+4*ga)+:8], dec_ctl_data[8*(3+4*ga)+:8],
                                       dec_ctl_data[8*(4+4*ga)+:8], dec_ctl_data[8*(5+4*ga)+:8]};
    end
  endgenerate
  always @(posedge clk) begin
    setpos_q_reg <= dec_setpos_wr;
    if (rst) setpos_q_reg <= 1'b0;
  end

  generate
    if (TRIG_EN != 0) begin : g_trig
      wire [0:0] probe_q, probe_strobe;
      input_filter #(
          .N          (1),
          .FILTER_CLKS(PROBE_FILTER_CLKS),
          .ACTIVE_LOW (PROBE_ACTIVE_LOW[0])
      ) u_probe_filter (
          .clk   (clk),
          .rst   (rst),
          .din   (probe_in),
          .q     (probe_q),
          .strobe(probe_strobe)
      );
      assign probe_lvl = probe_q[0] && (PROBE_ENABLE != 0);

      // TRIGGER mask u16 (payload bytes 1, 2): bit a = min of axis a, 8 + a its max (axes 0..7)
      wire [15:0] mask16 = {dec_ctl_data[15:8], dec_ctl_data[23:16]};
      reg [2*N_AXES-1:0] mask_w;
      reg [15:0] fired16;
      wire [2*N_AXES-1:0] fired_w;
      wire trig_armed, trig_done;
      wire [1:0] trig_mode;
      integer i;
      always @(*) begin
        mask_w  = {2 * N_AXES{1'b0}};
        fired16 = 16'd0;
        for (i = 0; i < N_AXES && i < 8; i = i + 1) begin
          mask_w[i]          = mask16[i];
          mask_w[N_AXES+i]   = mask16[8+i];
          fired16[i]         = fired_w[i];
          fired16[8+i]       = fired_w[N_AXES+i];
        end
      end

      trigger_latch #(
          .N_AXES(N_AXES)
      ) u_trigger (
          .clk         (clk),
          .rst         (rst),
          .wr          (dec_trig_wr),
          .wr_mode     (dec_ctl_data[1:0]),
          .wr_mask     (mask_w),
          .sw_rise     (lim_strobe & {lim_max_w, lim_min_w}),
          .probe_strobe(probe_strobe[0] && (PROBE_ENABLE != 0)),
          .probe_q     (probe_lvl),
          .position    (position),
          .suppress    (trig_suppress),
          .flush       (trig_flush),
          .cancel      (trig_cancel),
          .armed       (trig_armed),
          .done        (trig_done),
          .mode        (trig_mode),
          .fired       (fired_w),
          .latched     (trig_pos)
      );
      assign trig_state = {6'd0, trig_mode, 6'd0, trig_done, trig_armed, fired16};

      // SET_POSITION: the position is the executor's counter plus an offset per axis
      position_offset #(
          .N_AXES(N_AXES)
      ) u_pos_offset (
          .clk     (clk),
          .rst     (rst),
          .raw     (exec_position),
          .wr      (setpos_wr),
          .wdata   (setpos_data),
          .position(position)
      );
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_ctl = &{1'b0, dec_ctl_data[7:2]};
      /* verilator lint_on UNUSEDSIGNAL */
    end else begin : g_notrig
      assign probe_lvl     = 1'b0;
      assign trig_suppress = {2 * N_AXES{1'b0}};
      assign trig_flush    = 1'b0;
      assign trig_cancel   = 1'b0;
      assign trig_state    = 32'd0;
      assign trig_pos      = {32 * N_AXES{1'b0}};
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_trig = &{1'b0, probe_in, dec_trig_wr, setpos_wr, setpos_data};
      assign position = exec_position;
      /* verilator lint_on UNUSEDSIGNAL */
    end
  endgenerate
  assign probe_state = probe_lvl;

  // ---------------------------------------------------------------- motion rate
  // feed hold, resume and the feed / rapid rates (docs/timing.md "Feed hold and overrides"):
  // the hold and cycle-start buttons through their filter, MOTION frames, feed_rate's enable of
  // every motion generator. The v1 build has neither: its motion advances in every clock.
  wire [1:0] btn_q, btn_strobe;
  wire [1:0] btn_rise = btn_strobe & btn_q & BUTTON_ENABLE;
  wire rate_adv, rate_hold, rate_stopped, rate_flush, exec_rapid;
  wire [32:0] rate_r;  // the motion rate (2^32 = 100 %): the M4 laser power's scale

  input_filter #(
      .N          (2),
      .FILTER_CLKS(LIMIT_FILTER_CLKS),
      .ACTIVE_LOW (BUTTON_ACTIVE_LOW)
  ) u_button_filter (
      .clk   (clk),
      .rst   (rst),
      .din   ({start_in, hold_in}),
      .q     (btn_q),
      .strobe(btn_strobe)
  );

  generate
    if (V2_EN != 0) begin : g_rate
      feed_rate #(
          .PERIOD_LOG2(RATE_PERIOD_LOG2),
          .RAMP0      (RATE_RAMP)
      ) u_rate (
          .clk       (clk),
          .rst       (rst),
          .load      (dec_motion_set),
          .set_hold  (dec_motion_data[0]),
          .set_resume(dec_motion_data[1]),
          .set_cancel(dec_motion_data[2]),
          .set_feed  ({dec_motion_data[15:8], dec_motion_data[23:16]}),
          .set_rapid ({dec_motion_data[31:24], dec_motion_data[39:32]}),
          .set_ramp  ({dec_motion_data[47:40], dec_motion_data[55:48], dec_motion_data[63:56],
                       dec_motion_data[71:64]}),
          .hold_req  (btn_rise[0]),
          .resume_req(btn_rise[1]),
          .cancel_req(trig_cancel),
          .rapid_seg (exec_rapid),
          .adv       (rate_adv),
          .hold      (rate_hold),
          .stopped   (rate_stopped),
          .flush     (rate_flush),
          .rate      (rate_r)
      );
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_motion = &{1'b0, dec_motion_data[7:3]};
      /* verilator lint_on UNUSEDSIGNAL */
    end else begin : g_norate
      assign rate_adv     = 1'b1;
      assign rate_hold    = 1'b0;
      assign rate_stopped = 1'b0;
      assign rate_flush   = 1'b0;
      assign rate_r       = 33'h1_0000_0000;
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_rate = &{1'b0, btn_rise, exec_rapid, dec_motion_set, dec_motion_data,
                           trig_cancel};
      /* verilator lint_on UNUSEDSIGNAL */
    end
  endgenerate

  // ---------------------------------------------------------------- step timing
  // active step timing (all axes) and the minimum dominant period, as used by prep and executor
  wire [16*N_AXES-1:0] cfg_high, cfg_low, cfg_setup, cfg_hold;
  wire [31:0] min_period;

  wire exec_idle;
  wire prep_busy;
  wire fifo_empty = (fifo_level_w == 16'd0);
  assign quiet = exec_idle && !prep_busy && fifo_empty;

  step_config #(
      .N_AXES   (N_AXES),
      .STEP_HIGH(STEP_HIGH),
      .STEP_LOW (STEP_LOW),
      .DIR_SETUP(DIR_SETUP),
      .DIR_HOLD (DIR_HOLD),
      .FIXED    (FIXED_EN)
  ) u_step_cfg (
      .clk       (clk),
      .rst       (rst),
      .cfg_wr    (cfg_wr),
      .cfg_addr  (cfg_addr),
      .cfg_wdata (cfg_wdata),
      .frame_wr  (dec_cfg_wr),
      .frame_axis(dec_cfg_axis),
      .frame_data(dec_cfg_data),
      .quiet     (quiet),
      .cfg_high  (cfg_high),
      .cfg_low   (cfg_low),
      .cfg_setup (cfg_setup),
      .cfg_hold  (cfg_hold),
      .min_period(min_period)
  );

  // ---------------------------------------------------------------- preparation
  wire [1:0] seg_code;
  wire [7:0] seg_power;
  wire seg_v2, seg_dir_fast;
  wire [N_AXES-1:0] seg_dir;
  wire [32*N_AXES-1:0] seg_steps;
  wire [64*N_AXES-1:0] seg_tmn;
  wire [63:0] seg_total;
  wire [15:0] seg_feed;
  wire [31:0] seg_period;
  wire seg_tvalid, seg_tready;
  wire init_applied, init_v2, prep_clamped;
  // PROFILE segments (LINE_PROFILE): segment_prep -> segment_executor
  wire [1:0] seg_kind, seg_p_op1;
  wire [46:0] seg_p_u1, seg_p_v1, seg_p_vcruise, seg_p_vexit;
  wire [47:0] seg_p_vcma, seg_p_vxpa;
  wire [31:0] seg_p_accel, seg_p_decel_at;
  wire [23:0] seg_p_n_dom;
  wire [71*N_AXES-1:0] seg_p_v0, seg_p_vc, seg_p_vx;
  wire [56*N_AXES-1:0] seg_p_acc;
  wire [944:0] seg_arc;  // ARC segments: segment_prep -> segment_executor (arc_dda's inputs)
  wire [1:0] seg_arc_plane;  // and their plane (0 XY, 1 ZX, 2 YZ)
  // e-stop or limit alarm: prep and executor drop what they hold, stay idle
  // (or a completed HOME: trigger_latch's flush)
  assign motion_abort = estop_stop || limit_trip_w || rate_flush || trig_flush;
  wire out_tvalid, out_tready;  // OUTPUT entries: segment_prep -> segment_executor
  wire [23:0] out_tdata;

  segment_prep #(
      .N_AXES           (N_AXES),
      .PROFILES         (PROF_EN),
      .ARCS             (ARC_EN),
      .V1_ONLY          (TRIM_EN),
      .OUTPUTS          (OUT_EN),
      .FEED0_PERIOD     (FEED0_PERIOD),
      .DEFAULT_NUMERATOR(DEFAULT_NUMERATOR)
  ) u_prep (
      .clk            (clk),
      .rst            (rst),
      .abort          (motion_abort),
      .s_axis_tdata   (cmd_tdata),
      .s_axis_tvalid  (cmd_tvalid),
      .s_axis_tready  (cmd_tready),
      .exec_idle      (exec_idle),
      .min_period     (min_period),
      .cfg_dir_setup  (cfg_setup),
      .cfg_dir_hold   (cfg_hold),
      .m_axis_code    (seg_code),
      .m_axis_power   (seg_power),
      .m_axis_v2      (seg_v2),
      .m_axis_dir_fast(seg_dir_fast),
      .m_axis_dir     (seg_dir),
      .m_axis_steps   (seg_steps),
      .m_axis_tmn     (seg_tmn),
      .m_axis_total   (seg_total),
      .m_axis_period  (seg_period),
      .m_axis_feed    (seg_feed),
      .m_axis_kind    (seg_kind),
      .m_axis_prof_u1 (seg_p_u1),
      .m_axis_prof_v1 (seg_p_v1),
      .m_axis_prof_op1(seg_p_op1),
      .m_axis_prof_accel   (seg_p_accel),
      .m_axis_prof_vcruise (seg_p_vcruise),
      .m_axis_prof_vexit   (seg_p_vexit),
      .m_axis_prof_vcma    (seg_p_vcma),
      .m_axis_prof_vxpa    (seg_p_vxpa),
      .m_axis_prof_decel_at(seg_p_decel_at),
      .m_axis_prof_n_dom   (seg_p_n_dom),
      .m_axis_prof_v0      (seg_p_v0),
      .m_axis_prof_vc      (seg_p_vc),
      .m_axis_prof_vx      (seg_p_vx),
      .m_axis_prof_acc     (seg_p_acc),
      .m_axis_arc          (seg_arc),
      .m_axis_arc_plane    (seg_arc_plane),
      .m_axis_tvalid  (seg_tvalid),
      .m_axis_tready  (seg_tready),
      .m_out_tvalid   (out_tvalid),
      .m_out_tdata    (out_tdata),
      .m_out_tready   (out_tready),
      .numerator_x    (numerator_x),
      .numerator_y    (numerator_y),
      .init_applied   (init_applied),
      .init_v2        (init_v2),
      .clamped        (prep_clamped),
      .busy           (prep_busy)
  );

  // ---------------------------------------------------------------- execution
  wire exec_busy, exec_violation, seg_done_v2, exec_arc_err;
  wire exec_laser;
  wire exec_flood, exec_mist;
  wire [3:0] exec_dout;
  wire [7:0] exec_fan_duty;
  wire exec_laser_dyn, exec_prof_run;
  wire [7:0] exec_power;
  wire [46:0] exec_prof_v, exec_prof_vc;
  wire out_done;
  wire [15:0] out_done_n;

  segment_executor #(
      .N_AXES        (N_AXES),
      .PROFILES      (PROF_EN),
      .ARCS          (ARC_EN),
      .LEAN_DDA      (TRIM_EN),
      .OUTPUTS       (OUT_EN)
  ) u_exec (
      .clk            (clk),
      .rst            (rst),
      .s_axis_code    (seg_code),
      .s_axis_power   (seg_power),
      .s_axis_v2      (seg_v2),
      .s_axis_dir_fast(seg_dir_fast),
      .s_axis_dir     (seg_dir),
      .s_axis_steps   (seg_steps),
      .s_axis_tmn     (seg_tmn),
      .s_axis_total   (seg_total),
      .s_axis_kind    (seg_kind),
      .s_axis_prof_u1 (seg_p_u1),
      .s_axis_prof_v1 (seg_p_v1),
      .s_axis_prof_op1(seg_p_op1),
      .s_axis_prof_accel   (seg_p_accel),
      .s_axis_prof_vcruise (seg_p_vcruise),
      .s_axis_prof_vexit   (seg_p_vexit),
      .s_axis_prof_vcma    (seg_p_vcma),
      .s_axis_prof_vxpa    (seg_p_vxpa),
      .s_axis_prof_decel_at(seg_p_decel_at),
      .s_axis_prof_n_dom   (seg_p_n_dom),
      .s_axis_prof_v0      (seg_p_v0),
      .s_axis_prof_vc      (seg_p_vc),
      .s_axis_prof_vx      (seg_p_vx),
      .s_axis_prof_acc     (seg_p_acc),
      .s_axis_arc          (seg_arc),
      .s_axis_arc_plane    (seg_arc_plane),
      .s_axis_tvalid  (seg_tvalid),
      .s_axis_tready  (seg_tready),
      .s_out_tvalid   (out_tvalid),
      .s_out_tdata    (out_tdata),
      .s_out_tready   (out_tready),
      .cfg_step_high  (cfg_high),
      .cfg_step_low   (cfg_low),
      .cfg_dir_setup  (cfg_setup),
      .cfg_dir_hold   (cfg_hold),
      .abort          (motion_abort),
      .adv            (rate_adv),
      .rapid_seg      (exec_rapid),
      .step_block     (exec_step_block),
      .step_want      (exec_step_want),
      .step           (step),
      .dir            (dir),
      .laser          (exec_laser),
      .busy           (exec_busy),
      .idle           (exec_idle),
      .running        (running),
      .seg_start      (seg_start),
      .seg_done       (seg_done),
      .seg_done_v2    (seg_done_v2),
      .position       (exec_position),
      .violation      (exec_violation),
      .arc_err        (exec_arc_err),
      .coolant_flood  (exec_flood),
      .coolant_mist   (exec_mist),
      .dout           (exec_dout),
      .fan_duty       (exec_fan_duty),
      .laser_dyn      (exec_laser_dyn),
      .power          (exec_power),
      .prof_run       (exec_prof_run),
      .prof_v         (exec_prof_v),
      .prof_vc        (exec_prof_vc),
      .out_done       (out_done),
      .out_done_n     (out_done_n)
  );

  // ---------------------------------------------------------------- machine outputs
  machine_outputs #(
      .CLK_HZ    (CLK_HZ),
      .FAN_PWM_HZ(FAN_PWM_HZ),
      .LASER_PWM_HZ(LASER_PWM_HZ),
      .OUTPUTS   (OUT_EN)
  ) u_outputs (
      .clk          (clk),
      .rst          (rst),
      .abort        (motion_abort),
      .exec_laser   (exec_laser && !rate_stopped),
      .exec_flood   (exec_flood),
      .exec_mist    (exec_mist),
      .exec_dout    (exec_dout),
      .exec_fan_duty(exec_fan_duty),
      .exec_power   (exec_power),
      .exec_dyn     (exec_laser_dyn),
      .exec_prof    (exec_prof_run),
      .exec_v       (exec_prof_v),
      .exec_vc      (exec_prof_vc),
      .rate         (rate_r),
      .laser        (laser),
      .coolant_flood(coolant_flood),
      .coolant_mist (coolant_mist),
      .dout         (dout),
      .fan          (fan),
      .spindle_pwm  (spindle_pwm)
  );

  // ---------------------------------------------------------------- status
  wire v2_seg_done = seg_done && seg_done_v2;
  wire v2_init_done = init_applied && init_v2;
  wire v1_move_done = seg_done && !seg_done_v2;
  wire [15:0] frames_ok_w, crc_errors_w, length_errors_w, unknown_types_w, timeouts_w;
  wire [15:0] frame_errors_w, overruns_w, noise_bytes_w, clamped_w;
  wire [31:0] segments_done_w;
  wire [7:0] faults_w;
  wire [127:0] heat_status;
  wire [7:0] heat_faults0, heat_faults1;
  wire heat_wd_fault;

  status_counters u_status (
      .clk           (clk),
      .rst           (rst),
      .seg_accept    (seg_tvalid && seg_tready),
      .seg_code      (seg_code),
      .seg_feed      (seg_feed),
      .seg_period    (seg_period),
      .v1_packet     (dec_v1_packet),
      .frame_ok      (dec_frame_ok),
      .rx_frame_error(rx_frame_error),
      .timeout       (dec_timeout),
      .v1_overrun    (dec_v1_overrun),
      .rx_overrun    (rx_overrun),
      .violation     (exec_violation),
      .crc_error     (dec_crc_error),
      .length_error  (dec_length_error),
      .unknown_type  (dec_unknown_type),
      .noise         (dec_noise),
      .prep_clamped  (prep_clamped),
      .nak           (dec_nak),
      .v2_seg_done   (v2_seg_done),
      .v2_init_done  (v2_init_done),
      .out_done      (out_done),
      .out_done_n    (out_done_n),
      .fault_clear   (dec_fault_clear),
      .arc_err       (exec_arc_err),
      .heat_faults0  (heat_faults0),
      .heat_faults1  (heat_faults1),
      .heat_wd_fault (heat_wd_fault),
      .estop_latched (estop_latched),
      .limit_trip    (limit_trip_w),
      .last_code     (last_code),
      .last_feed     (last_feed),
      .last_period   (last_period),
      .packet_count  (packet_count),
      .frame_errors  (frame_errors_w),
      .timeouts      (timeouts_w),
      .overruns      (overruns_w),
      .violations    (violations),
      .frames_ok     (frames_ok_w),
      .crc_errors    (crc_errors_w),
      .length_errors (length_errors_w),
      .unknown_types (unknown_types_w),
      .noise_bytes   (noise_bytes_w),
      .clamped       (clamped_w),
      .naks          (naks),
      .segments_done (segments_done_w),
      .faults        (faults_w)
  );

  // ---------------------------------------------------------------- heaters
  generate
    if (HEAT_EN != 0) begin : g_heat
      /* verilator lint_off UNUSEDSIGNAL */
      wire heat_tick, heat_done;
      /* verilator lint_on UNUSEDSIGNAL */
      heater_block #(
          .SAMPLE_CLKS(SAMPLE_CLKS),
          .PWM_BITS   (HEAT_PWM_BITS),
          .PWM_DIV    (HEAT_PWM_DIV)
      ) u_heat (
          .clk        (clk),
          .rst        (rst),
          .frame_wr   (dec_heat_wr),
          .frame_type (dec_heat_type),
          .frame_len  (dec_heat_len),
          .frame_data (dec_heat_data),
          .frame_ok   (dec_frame_ok),
          .fault_clear(dec_fault_clear),
          .estop      (estop_stop),
          .heater     (heater),
          .heat_status(heat_status),
          .faults0    (heat_faults0),
          .faults1    (heat_faults1),
          .wd_fault   (heat_wd_fault),
          .tick       (heat_tick),
          .sample_done(heat_done),
          .adc_convst (adc_convst),
          .adc_sck    (adc_sck),
          .adc_sdi    (adc_sdi),
          .adc_sdo    (adc_sdo)
      );
    end else begin : g_noheat
      assign heater       = 2'b00;
      assign adc_convst   = 1'b0;
      assign adc_sck      = 1'b0;
      assign adc_sdi      = 1'b0;
      assign heat_status  = 128'd0;
      assign heat_faults0 = 8'd0;
      assign heat_faults1 = 8'd0;
      assign heat_wd_fault = 1'b0;
      // inputs of the heater path not used without heaters
      wire unused_heat = &{1'b0, adc_sdo, dec_heat_wr, dec_heat_type, dec_heat_len, dec_heat_data};
    end
  endgenerate

  // ---------------------------------------------------------------- answers
  wire [7:0] enc_tdata;
  wire enc_tvalid, tx_tready;

  answer_source #(
      .PROTO_V2  (V2_EN),
      .N_AXES    (N_AXES),
      .FIFO_DEPTH(FIFO_DEPTH),
      .CLK_HZ    (CLK_HZ),
      .BAUD      (BAUD),
      .BUILD_ID  (BUILD_ID)
  ) u_answer (
      .clk            (clk),
      .rst            (rst),
      .ident_req      (dec_hello),
      .status_req     (dec_status),
      .trig_req       (dec_trig_query),
      .nak_req        (dec_nak),
      .nak_seq        (dec_nak_seq),
      .nak_reason     (dec_nak_reason),
      .ack_req        (dec_ack),
      .done_evt       (v2_seg_done || v2_init_done || out_done),
      .v1_ack         (v1_move_done),
      .next_seq       (dec_next_seq),
      .fifo_free      (fifo_free_w),
      .fifo_level     (fifo_level_w),
      .segments_done  (segments_done_w),
      .busy           (busy),
      .v2_mode        (dec_v2_mode),
      .estop_active   (estop_active),
      .limit_untrusted(limit_untrusted),
      .hold           (rate_hold),
      .stopped        (rate_stopped),
      .probe          (probe_lvl),
      .faults         (faults_w),
      .position       (position),
      .counters       ({frames_ok_w, crc_errors_w, length_errors_w, unknown_types_w, timeouts_w,
                        frame_errors_w, overruns_w, noise_bytes_w, clamped_w}),
      .limit_trip_max (limit_trip_max),
      .limit_trip_axis(limit_trip_axis),
      .lim_min        (lim_min_w),
      .lim_max        (lim_max_w),
      .heat_status    (heat_status),
      .trig_state     (trig_state),
      .trig_pos       (trig_pos),
      .m_axis_tdata   (enc_tdata),
      .m_axis_tvalid  (enc_tvalid),
      .m_axis_tready  (tx_tready)
  );

  uart_tx #(
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD)
  ) u_tx (
      .clk          (clk),
      .rst          (rst),
      .s_axis_tdata (enc_tdata),
      .s_axis_tvalid(enc_tvalid),
      .s_axis_tready(tx_tready),
      .txd          (tx),
      .busy         (tx_busy)
  );

  // ---------------------------------------------------------------- pins
  assign busy          = exec_busy || prep_busy || !fifo_empty;
  assign frame_errors  = frame_errors_w;
  assign timeouts      = timeouts_w;
  assign overruns      = overruns_w;
  assign fifo_level    = fifo_level_w;
  assign next_seq      = dec_next_seq;
  assign v2_mode       = dec_v2_mode;
  assign segments_done = segments_done_w;
  assign faults        = faults_w;
  assign frames_ok     = frames_ok_w;
  assign crc_errors    = crc_errors_w;
  assign length_errors = length_errors_w;
  assign unknown_types = unknown_types_w;
  assign noise_bytes   = noise_bytes_w;
  assign clamped       = clamped_w;

endmodule

`default_nettype wire
