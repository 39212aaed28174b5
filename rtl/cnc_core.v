// cnc_core: the board-independent controller, protocols v1 and v2: wiring of the blocks in
// docs/architecture.md ("Code flow in the device"), the configuration registers, the fault latch,
// the e-stop and the status counters.
//
// Contract
//   rx / tx          the UART (BAUD, 8N1); the protocol is docs/protocol.md.
//   step, dir, laser the motion pins (docs/timing.md); coolant_flood, coolant_mist, fan (PWM at
//                    about FAN_PWM_HZ), dout: machine outputs set by OUTPUT entries on the edge
//                    that ends the segment before them; low after rst and on e-stop.
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
//   1 each of PROFILES, ARCS, HEATERS, OUTPUTS = 0 removes its block and answers its frames NAK
//   UNKNOWN_TYPE. LEAN_TRIM = 1 and STEP_CFG = 0 (PROTO_V2 = 0 only) trim the v1 datapath and fix
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
    parameter LEAN_TRIM         = (PROTO_V2 == 0) ? 1 : 0,  // 1: PROTO_V2 = 0 only
    parameter STEP_CFG          = 1,                   // 0: PROTO_V2 = 0 only
    // hard limits (docs/machine.md): bit a = min switch of axis a, bit 16 + a = max switch
    parameter LIMIT_FILTER_CLKS = `FPGACNC_DEF_LIMIT_FILTER_CLKS,  // debounce, clocks
    parameter [31:0] LIMIT_ENABLE     = `FPGACNC_DEF_LIMIT_ENABLE,      // switches wired
    parameter [31:0] LIMIT_ACTIVE_LOW = `FPGACNC_DEF_LIMIT_ACTIVE_LOW   // asserted at a low pin
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

    input  wire       estop,       // e-stop, active high, asynchronous
    input  wire [N_AXES-1:0] limit_min,  // limit switches, asynchronous (LIMIT_* parameters)
    input  wire [N_AXES-1:0] limit_max,
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
    output wire                limit_trip      // the hard-limit alarm (faults bit 2)
);

  // FIFO entry (segment_prep header, LINE_PROFILE and ARC fields): 839 bits for 4 axes
  localparam ENTRY_W = `FPGACNC_ENTRY_W + 32 * N_AXES;
  // build options in effect (v1 carries no profiles, arcs or heater frames)
  localparam integer V2_EN = (PROTO_V2 != 0) ? 1 : 0;
  localparam integer PROF_EN = (V2_EN != 0 && PROFILES != 0) ? 1 : 0;
  localparam integer ARC_EN = (V2_EN != 0 && ARCS != 0) ? 1 : 0;
  localparam integer HEAT_EN = (V2_EN != 0 && HEATERS != 0) ? 1 : 0;
  localparam integer OUT_EN = (V2_EN != 0 && OUTPUTS != 0) ? 1 : 0;
  // fan PWM: 256 counts a period, PWM_DIV clocks a count (rounded): the frequency must come within
  // 1 % of FAN_PWM_HZ (checked at elaboration below)
  localparam integer FAN_HZ_I = (FAN_PWM_HZ < 1) ? 1 : FAN_PWM_HZ;
  localparam integer FAN_DIV_R = (CLK_HZ + 128 * FAN_HZ_I) / (256 * FAN_HZ_I);
  localparam integer FAN_DIV = (FAN_DIV_R < 1) ? 1 : FAN_DIV_R;
  localparam integer FAN_PERIOD = 256 * FAN_DIV;
  localparam integer FAN_ERR = (CLK_HZ > FAN_PERIOD * FAN_HZ_I) ? CLK_HZ - FAN_PERIOD * FAN_HZ_I
                                                                : FAN_PERIOD * FAN_HZ_I - CLK_HZ;
  localparam integer FAN_OK = (FAN_PWM_HZ >= 1 && FAN_DIV_R >= 1 &&
                               FAN_ERR <= FAN_PERIOD * FAN_HZ_I / 100) ? 1 : 0;
  // v1-only datapath trims (segment_prep V1_ONLY, executor LEAN_DDA)
  localparam integer TRIM_EN = (V2_EN == 0 && LEAN_TRIM != 0) ? 1 : 0;
  // v1 build with the step timing fixed at STEP_HIGH / STEP_LOW / DIR_SETUP / DIR_HOLD
  localparam integer FIXED_EN = (V2_EN == 0 && STEP_CFG == 0) ? 1 : 0;
  // the FIFO holds only the fields of the kinds built: header 45 + 32 * N_AXES, + 177 profile
  // fields, + 489 ARC fields (segment_prep's entry layout; the bits above are 0)
  localparam integer FIFO_W = (ARC_EN != 0)  ? ENTRY_W :
                              (PROF_EN != 0) ? `FPGACNC_ENTRY_PROF_W + 32 * N_AXES
                                             : `FPGACNC_ENTRY_BASE_W + 32 * N_AXES;

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

  // ---------------------------------------------------------------- decoder, command FIFO
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
  wire [7:0] dec_nak_seq, dec_nak_reason;
  wire estop_stop;  // e-stop active or latched (below)
  wire motion_abort;  // e-stop or hard-limit alarm: FIFO flushed, prep and executor aborted

  generate
    if (V2_EN != 0) begin : g_v2
      wire [ENTRY_W-1:0] dec_tdata;
      wire dec_tvalid, fifo_s_tready;
      /* verilator lint_off UNUSEDSIGNAL */
      wire dec_release;  // not needed here
      /* verilator lint_on UNUSEDSIGNAL */

      frame_decoder #(
          .N_AXES       (N_AXES),
          .WATCHDOG_CLKS(WATCHDOG_CLKS),
          .MAX_PAYLOAD  (64),
          .PROFILES     (PROF_EN),
          .ARCS         (ARC_EN),
          .OUTPUTS      (OUT_EN),
          .HEATERS      (HEAT_EN)
      ) u_dec (
          .clk          (clk),
          .rst          (rst),
          .s_axis_tdata (rx_tdata),
          .s_axis_tvalid(rx_tvalid),
          .s_axis_tready(rx_tready),
          .m_axis_tdata (dec_tdata),
          .m_axis_tvalid(dec_tvalid),
          .m_axis_tready(fifo_s_tready),
          .cfg_wr       (dec_cfg_wr),
          .cfg_axis     (dec_cfg_axis),
          .cfg_data     (dec_cfg_data),
          .heat_wr      (dec_heat_wr),
          .heat_type    (dec_heat_type),
          .heat_len     (dec_heat_len),
          .heat_data    (dec_heat_data),
          .fault_clear  (dec_fault_clear),
          .release_req  (dec_release),
          .hello        (dec_hello),
          .status_req   (dec_status),
          .ack_req      (dec_ack),
          .nak          (dec_nak),
          .nak_seq      (dec_nak_seq),
          .nak_reason   (dec_nak_reason),
          .travel_resync(motion_abort),
          .position     (position),
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

      // command FIFO: only the entry fields of the kinds built are stored
      wire [FIFO_W-1:0] fifo_out;
      /* verilator lint_off UNUSEDSIGNAL */
      wire [ENTRY_W-1:0] dec_tdata_nc = dec_tdata;  // bits above FIFO_W are 0 in a lean build
      /* verilator lint_on UNUSEDSIGNAL */

      segment_fifo #(
          .WIDTH(FIFO_W),
          .DEPTH(FIFO_DEPTH)
      ) u_fifo (
          .clk          (clk),
          .rst          (rst),
          .flush        (motion_abort),
          .s_axis_tdata (dec_tdata[FIFO_W-1:0]),
          .s_axis_tvalid(dec_tvalid),
          .s_axis_tready(fifo_s_tready),
          .m_axis_tdata (fifo_out),
          .m_axis_tvalid(cmd_tvalid),
          .m_axis_tready(cmd_tready),
          .level        (fifo_level_w),
          .free         (fifo_free_w)
      );
      if (FIFO_W < ENTRY_W) begin : g_pad
        assign cmd_tdata = {{(ENTRY_W - FIFO_W) {1'b0}}, fifo_out};
      end else begin : g_nopad
        assign cmd_tdata = fifo_out;
      end
    end else begin : g_v1
      // protocol v1 only: the original's decoder, its output register is the only queue
      wire [81:0] v1_tdata;
      wire v1_init;
      packet_decoder_v1 #(
          .WATCHDOG_CLKS(WATCHDOG_CLKS)
      ) u_dec (
          .clk          (clk),
          .rst          (rst),
          .s_axis_tdata (rx_tdata),
          .s_axis_tvalid(rx_tvalid),
          .s_axis_tready(rx_tready),
          .m_axis_tdata (v1_tdata),
          .m_axis_tuser (v1_init),
          .m_axis_tvalid(cmd_tvalid),
          .m_axis_tready(cmd_tready),
          .timeout      (dec_timeout),
          .overrun      (dec_v1_overrun),
          .packet_done  (dec_v1_packet),
          .partial      (rx_partial)
      );
      // segment_prep's entry (as frame_decoder writes a v1 packet): motion {v2 0, kind 0, code,
      // power 0xFF, t = feed, steps X, Y}; init {v2 0, kind 1, NUMERATOR_X, NUMERATOR_Y}
      wire [32*N_AXES-1:0] v1_two = {{32 * (N_AXES - 2) {1'b0}}, v1_tdata[47:16], v1_tdata[79:48]};
      assign cmd_tdata = {{(ENTRY_W - `FPGACNC_ENTRY_BASE_W - 32 * N_AXES) {1'b0}}, 1'b0,
                          v1_init ? `FPGACNC_K_NUMERATORS : `FPGACNC_K_MOTION,
                          v1_init ? 2'd0 : v1_tdata[81:80],
                          v1_init ? 8'd0 : 8'hFF, v1_init ? 16'd0 : 16'd0,
                          v1_init ? 16'd0 : v1_tdata[15:0], v1_two};
      assign fifo_level_w     = {15'd0, cmd_tvalid};
      assign fifo_free_w      = {15'd0, !cmd_tvalid};
      assign dec_hello        = 1'b0;
      assign dec_status       = 1'b0;
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
  reg estop_s1_reg, estop_s2_reg, estop_latch_reg;
  always @(posedge clk) begin
    estop_s1_reg <= estop;
    estop_s2_reg <= estop_s1_reg;
    if (dec_fault_clear && !estop_s2_reg) estop_latch_reg <= 1'b0;
    if (estop_s2_reg) estop_latch_reg <= 1'b1;
    if (rst) begin
      estop_s1_reg    <= 1'b0;
      estop_s2_reg    <= 1'b0;
      estop_latch_reg <= 1'b0;
    end
  end
  assign estop_stop = estop_s2_reg || estop_latch_reg;  // motion, laser, heaters stopped

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
      .block    (exec_step_block),
      .trip     (limit_trip_w),
      .trip_axis(limit_trip_axis),
      .trip_max (limit_trip_max),
      .untrusted(limit_untrusted)
  );
  assign limit_state = {lim_max_w, lim_min_w};
  assign limit_trip  = limit_trip_w;

  // ---------------------------------------------------------------- configuration
  // active step timing (all axes) and the minimum dominant period, as used by prep and executor
  wire [16*N_AXES-1:0] cfg_high, cfg_low, cfg_setup, cfg_hold;
  wire [31:0] min_period;

  wire exec_idle;
  wire prep_busy;
  wire fifo_empty = (fifo_level_w == 16'd0);
  wire quiet = exec_idle && !prep_busy && fifo_empty;

  // min_period = max over axes of (STEP high + STEP low), each at least 1, so at least 2: the fastest dominant period
  // the pulse generators can follow. Computed by a scanner, one axis per clock (no comparator
  // chain across axes): a change of the active settings reaches min_period_reg within
  // 2 * N_AXES + 2 clocks, long before segment_prep uses it (34 clocks after it accepts a move,
  // and settings change only while segment_prep is idle). Requires N_AXES <= 15.
  localparam AXW = (N_AXES > 1) ? $clog2(N_AXES) : 1;
  localparam integer AX_LAST_I = N_AXES - 1;
  localparam [AXW-1:0] AX_LAST = AX_LAST_I[AXW-1:0];
  localparam integer NAX_I = N_AXES;
  localparam [7:0] NAX8 = NAX_I[7:0];
  // fixed timing (STEP_CFG = 0, v1 build): a setting of 0 counts as 1 clock, as in step_pulse
  localparam integer FIX_PERIOD_I = ((STEP_HIGH == 0) ? 1 : STEP_HIGH) + ((STEP_LOW == 0) ? 1 : STEP_LOW);
  localparam [31:0] FIX_PERIOD = FIX_PERIOD_I;

  generate
  if (FIXED_EN == 0) begin : g_cfg
  reg [16*N_AXES-1:0] shadow_high_reg, shadow_low_reg, shadow_setup_reg, shadow_hold_reg;
  reg [16*N_AXES-1:0] cfg_high_reg, cfg_low_reg, cfg_setup_reg, cfg_hold_reg;
  reg [31:0] min_period_reg;
  reg [AXW-1:0] pm_idx_reg, pm_idx_d_reg;
  reg [16:0] pm_sum_reg, pm_run_reg;
  // step_pulse treats a setting of 0 as 1 clock: count it so here too.
  wire [15:0] pm_high_raw = cfg_high_reg[16*pm_idx_reg+:16];
  wire [15:0] pm_low_raw = cfg_low_reg[16*pm_idx_reg+:16];
  wire [15:0] pm_high = (pm_high_raw == 16'd0) ? 16'd1 : pm_high_raw;
  wire [15:0] pm_low = (pm_low_raw == 16'd0) ? 16'd1 : pm_low_raw;
  wire [16:0] pm_cand = (pm_idx_d_reg == {AXW{1'b0}} || pm_sum_reg > pm_run_reg) ? pm_sum_reg
                                                                                 : pm_run_reg;

  wire [AXW-1:0] dec_ax = dec_cfg_axis[AXW-1:0];

  always @(posedge clk) begin
    if (dec_cfg_wr && dec_cfg_axis < NAX8) begin
      shadow_high_reg[16*dec_ax+:16]  <= dec_cfg_data[63:48];
      shadow_low_reg[16*dec_ax+:16]   <= dec_cfg_data[47:32];
      shadow_setup_reg[16*dec_ax+:16] <= dec_cfg_data[31:16];
      shadow_hold_reg[16*dec_ax+:16]  <= dec_cfg_data[15:0];
    end
    if (cfg_wr && {2'b00, cfg_addr[7:2]} < NAX8) begin
      case (cfg_addr[1:0])
        2'd0: shadow_high_reg[16*cfg_addr[7:2]+:16] <= cfg_wdata;
        2'd1: shadow_low_reg[16*cfg_addr[7:2]+:16] <= cfg_wdata;
        2'd2: shadow_setup_reg[16*cfg_addr[7:2]+:16] <= cfg_wdata;
        default: shadow_hold_reg[16*cfg_addr[7:2]+:16] <= cfg_wdata;
      endcase
    end
    if (quiet) begin
      cfg_high_reg  <= shadow_high_reg;
      cfg_low_reg   <= shadow_low_reg;
      cfg_setup_reg <= shadow_setup_reg;
      cfg_hold_reg  <= shadow_hold_reg;
    end
    pm_idx_reg   <= (pm_idx_reg == AX_LAST) ? {AXW{1'b0}} : pm_idx_reg + 1'b1;
    pm_idx_d_reg <= pm_idx_reg;
    pm_sum_reg   <= {1'b0, pm_high} + {1'b0, pm_low};
    pm_run_reg   <= pm_cand;
    // STEP high and low are each at least one clock, so a period of at least 2.
    if (pm_idx_d_reg == AX_LAST) min_period_reg <= (pm_cand < 17'd2) ? 32'd2 : {15'd0, pm_cand};
    if (rst) begin
      shadow_high_reg  <= {N_AXES{STEP_HIGH[15:0]}};
      shadow_low_reg   <= {N_AXES{STEP_LOW[15:0]}};
      shadow_setup_reg <= {N_AXES{DIR_SETUP[15:0]}};
      shadow_hold_reg  <= {N_AXES{DIR_HOLD[15:0]}};
      cfg_high_reg     <= {N_AXES{STEP_HIGH[15:0]}};
      cfg_low_reg      <= {N_AXES{STEP_LOW[15:0]}};
      cfg_setup_reg    <= {N_AXES{DIR_SETUP[15:0]}};
      cfg_hold_reg     <= {N_AXES{DIR_HOLD[15:0]}};
      min_period_reg   <= STEP_HIGH + STEP_LOW;
      pm_idx_reg       <= {AXW{1'b0}};
      pm_idx_d_reg     <= {AXW{1'b0}};
      pm_sum_reg       <= 17'd0;
      pm_run_reg       <= 17'd0;
    end
  end
  assign cfg_high   = cfg_high_reg;
  assign cfg_low    = cfg_low_reg;
  assign cfg_setup  = cfg_setup_reg;
  assign cfg_hold   = cfg_hold_reg;
  assign min_period = min_period_reg;
  end else begin : g_fixed
    // the defaults, constant: no shadow or active set, no scanner; the cfg port is not read
    assign cfg_high   = {N_AXES{STEP_HIGH[15:0]}};
    assign cfg_low    = {N_AXES{STEP_LOW[15:0]}};
    assign cfg_setup  = {N_AXES{DIR_SETUP[15:0]}};
    assign cfg_hold   = {N_AXES{DIR_HOLD[15:0]}};
    assign min_period = FIX_PERIOD;
    wire unused_cfg = &{1'b0, cfg_wr, cfg_addr, cfg_wdata, dec_cfg_wr, dec_cfg_axis, dec_cfg_data,
                        quiet};
  end
  endgenerate

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
  assign motion_abort = estop_stop || limit_trip_w;
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
  wire out_done;
  wire [15:0] out_done_n;
  assign laser = exec_laser && !motion_abort;  // also low at once (the executor's own is registered)

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
      .position       (position),
      .violation      (exec_violation),
      .arc_err        (exec_arc_err),
      .coolant_flood  (exec_flood),
      .coolant_mist   (exec_mist),
      .dout           (exec_dout),
      .fan_duty       (exec_fan_duty),
      .out_done       (out_done),
      .out_done_n     (out_done_n)
  );

  // ---------------------------------------------------------------- machine outputs
  // low at once on e-stop or a limit alarm (the executor clears its levels from the next edge)
  assign coolant_flood = exec_flood && !motion_abort;
  assign coolant_mist  = exec_mist && !motion_abort;
  assign dout          = exec_dout & {4{!motion_abort}};
  generate
    if (FAN_OK == 0) begin : g_fan_bad
      // FAN_PWM_HZ must be at least 1, at most CLK_HZ / 256, and reachable within 1 %
      FAN_PWM_HZ_out_of_range u_fan_pwm_hz_out_of_range ();
    end
    if (OUT_EN != 0) begin : g_fan
      wire fan_pwm, fan_start;
      /* verilator lint_off UNUSEDSIGNAL */
      wire [8:0] fan_active_nc;
      /* verilator lint_on UNUSEDSIGNAL */
      // The PWM takes a duty only at a period boundary: after an e-stop the pin stays low until
      // the first boundary (fan_start: the clock after it), from which the duty the executor
      // holds (0 after the e-stop, or a later OUTPUT's) is the active one.
      reg fan_hold_reg;
      always @(posedge clk) begin
        if (fan_start) fan_hold_reg <= 1'b0;
        if (motion_abort) fan_hold_reg <= 1'b1;
        if (rst) fan_hold_reg <= 1'b0;
      end
      pwm #(
          .PWM_BITS(8),
          .PWM_DIV (FAN_DIV)
      ) u_fan (
          .clk         (clk),
          .rst         (rst),
          .duty        ((exec_fan_duty == 8'hFF) ? 9'd256 : {1'b0, exec_fan_duty}),
          .force_off   (motion_abort),
          .out         (fan_pwm),
          .period_start(fan_start),
          .active      (fan_active_nc)
      );
      assign fan = fan_pwm && !motion_abort && !(fan_hold_reg && !fan_start);
    end else begin : g_nofan
      assign fan = 1'b0;
      wire unused_fan = &{1'b0, exec_fan_duty};
    end
  endgenerate

  // ---------------------------------------------------------------- status
  reg [1:0] last_code_reg;
  reg [15:0] last_feed_reg;
  reg [31:0] last_period_reg;
  reg [15:0] packet_count_reg, frame_errors_reg, timeouts_reg, overruns_reg, violations_reg;
  reg [15:0] frames_ok_reg, crc_errors_reg, length_errors_reg, unknown_types_reg;
  reg [15:0] noise_bytes_reg, clamped_reg, naks_reg;
  reg [31:0] segments_done_reg;
  reg fault_step_reg;
  reg fault_arc_reg;  // an ARC ended inconsistently (faults bit 1)

  wire v2_seg_done = seg_done && seg_done_v2;
  wire v2_init_done = init_applied && init_v2;
  wire v1_move_done = seg_done && !seg_done_v2;

  always @(posedge clk) begin
    if (seg_tvalid && seg_tready) begin
      last_code_reg   <= seg_code;
      last_feed_reg   <= seg_feed;
      last_period_reg <= seg_period;
    end
    if (dec_v1_packet || dec_frame_ok) packet_count_reg <= packet_count_reg + 16'd1;
    if (rx_frame_error) frame_errors_reg <= frame_errors_reg + 16'd1;
    if (dec_timeout) timeouts_reg <= timeouts_reg + 16'd1;
    if (dec_v1_overrun || rx_overrun) overruns_reg <= overruns_reg + 16'd1;
    if (exec_violation) violations_reg <= violations_reg + 16'd1;
    if (dec_frame_ok) frames_ok_reg <= frames_ok_reg + 16'd1;
    if (dec_crc_error) crc_errors_reg <= crc_errors_reg + 16'd1;
    if (dec_length_error) length_errors_reg <= length_errors_reg + 16'd1;
    if (dec_unknown_type) unknown_types_reg <= unknown_types_reg + 16'd1;
    if (dec_noise) noise_bytes_reg <= noise_bytes_reg + 16'd1;
    if (prep_clamped) clamped_reg <= clamped_reg + 16'd1;
    if (dec_nak) naks_reg <= naks_reg + 16'd1;
    segments_done_reg <= segments_done_reg + {31'd0, v2_seg_done} + {31'd0, v2_init_done} +
                         (out_done ? {16'd0, out_done_n} : 32'd0);
    if (dec_fault_clear) fault_step_reg <= 1'b0;
    if (exec_violation) fault_step_reg <= 1'b1;
    if (dec_fault_clear) fault_arc_reg <= 1'b0;
    if (exec_arc_err) fault_arc_reg <= 1'b1;
    if (rst) begin
      last_code_reg     <= 2'd0;
      last_feed_reg     <= 16'd0;
      last_period_reg   <= 32'd0;
      packet_count_reg  <= 16'd0;
      frame_errors_reg  <= 16'd0;
      timeouts_reg      <= 16'd0;
      overruns_reg      <= 16'd0;
      violations_reg    <= 16'd0;
      frames_ok_reg     <= 16'd0;
      crc_errors_reg    <= 16'd0;
      length_errors_reg <= 16'd0;
      unknown_types_reg <= 16'd0;
      noise_bytes_reg   <= 16'd0;
      clamped_reg       <= 16'd0;
      naks_reg          <= 16'd0;
      segments_done_reg <= 32'd0;
      fault_step_reg    <= 1'b0;
      fault_arc_reg     <= 1'b0;
    end
  end

  // ---------------------------------------------------------------- heaters
  wire [127:0] heat_status;
  wire [7:0] heat_faults0, heat_faults1;
  wire heat_wd_fault;
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
  wire [7:0] faults_w = {heat_faults1 != 8'd0, heat_faults0 != 8'd0, heat_wd_fault, estop_latch_reg,
                         1'b0, limit_trip_w, fault_arc_reg, fault_step_reg};

  generate
    if (V2_EN != 0) begin : g_enc
      /* verilator lint_off UNUSEDSIGNAL */
      wire enc_frame_start;  // not needed here
      /* verilator lint_on UNUSEDSIGNAL */
      wire [7:0] state_w = {3'd0, limit_untrusted, estop_s2_reg, faults_w != 8'd0, dec_v2_mode, busy};
      // STATUS limit byte {0, 0, 0, max, axis} of the last trip, switch states u16 (bit a = min
      // of axis a, bit 8 + a = max; axes 0..7)
      /* verilator lint_off UNUSEDSIGNAL */
      wire [15:0] lim_min16 = {{(16 - N_AXES) {1'b0}}, lim_min_w};  // axes 8..14 not reported
      wire [15:0] lim_max16 = {{(16 - N_AXES) {1'b0}}, lim_max_w};
      /* verilator lint_on UNUSEDSIGNAL */
      wire [23:0] limits_w = {3'd0, limit_trip_max, limit_trip_axis, lim_max16[7:0], lim_min16[7:0]};
      wire [16*9-1:0] counters_w = {frames_ok_reg, crc_errors_reg, length_errors_reg,
                                    unknown_types_reg, timeouts_reg, frame_errors_reg, overruns_reg,
                                    noise_bytes_reg, clamped_reg};

      response_encoder #(
          .N_AXES     (N_AXES),
          .FIFO_DEPTH (FIFO_DEPTH),
          .CLK_HZ     (CLK_HZ),
          .BAUD       (BAUD),
          .BUILD_ID   (BUILD_ID),
          .MAX_PAYLOAD(64),
          .HEAT_BYTES (16)
      ) u_enc (
          .clk          (clk),
          .rst          (rst),
          .ident_req    (dec_hello),
          .status_req   (dec_status),
          .nak_req      (dec_nak),
          .nak_seq      (dec_nak_seq),
          .nak_reason   (dec_nak_reason),
          .ack_req      (dec_ack),
          .done_evt     (v2_seg_done || v2_init_done || out_done),
          .v1_ack       (v1_move_done),
          .next_seq     (dec_next_seq),
          .fifo_free    (fifo_free_w),
          .fifo_level   (fifo_level_w),
          .segments_done(segments_done_reg),
          .state        (state_w),
          .faults       (faults_w),
          .position     (position),
          .counters     (counters_w),
          .limits       (limits_w),
          .heat_status  (heat_status),
          .m_axis_tdata (enc_tdata),
          .m_axis_tvalid(enc_tvalid),
          .m_axis_tready(tx_tready),
          .frame_start  (enc_frame_start)
      );
    end else begin : g_aa
      // v1: one 0xAA per completed v1 move (a counter, as response_encoder keeps it)
      reg [7:0] aa_cnt_reg;
      wire aa_take = enc_tvalid && tx_tready;
      always @(posedge clk) begin
        case ({v1_move_done, aa_take})
          2'b10:   aa_cnt_reg <= aa_cnt_reg + 8'd1;
          2'b01:   aa_cnt_reg <= aa_cnt_reg - 8'd1;
          default: aa_cnt_reg <= aa_cnt_reg;
        endcase
        if (rst) aa_cnt_reg <= 8'd0;
      end
      assign enc_tdata  = `FPGACNC_V1_ACK;
      assign enc_tvalid = (aa_cnt_reg != 8'd0);
      // v2-only status and requests, unused in a v1 build
      wire unused_v2 = &{1'b0, dec_hello, dec_status, dec_ack, dec_nak, dec_nak_seq, dec_nak_reason,
                         fifo_free_w, segments_done_reg, heat_status, v2_seg_done, v2_init_done,
                         frames_ok_reg, crc_errors_reg, length_errors_reg, unknown_types_reg,
                         noise_bytes_reg, clamped_reg, limit_untrusted, limit_trip_axis,
                         limit_trip_max};
    end
  endgenerate

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

  assign busy          = exec_busy || prep_busy || !fifo_empty;
  assign last_code     = last_code_reg;
  assign last_feed     = last_feed_reg;
  assign last_period   = last_period_reg;
  assign packet_count  = packet_count_reg;
  assign frame_errors  = frame_errors_reg;
  assign timeouts      = timeouts_reg;
  assign overruns      = overruns_reg;
  assign violations    = violations_reg;
  assign fifo_level    = fifo_level_w;
  assign next_seq      = dec_next_seq;
  assign v2_mode       = dec_v2_mode;
  assign segments_done = segments_done_reg;
  assign faults        = faults_w;
  assign frames_ok     = frames_ok_reg;
  assign crc_errors    = crc_errors_reg;
  assign length_errors = length_errors_reg;
  assign unknown_types = unknown_types_reg;
  assign noise_bytes   = noise_bytes_reg;
  assign clamped       = clamped_reg;
  assign naks          = naks_reg;

endmodule

`default_nettype wire
