// frame_decoder: one decoder for protocol v1 packets and v2 frames (docs/protocol.md "Telling v1
// from v2", "Frame", "Host to device"; its place in the core: docs/architecture.md).
//
// Contract
//   s_axis_*    bytes from uart_rx; s_axis_tready is always high (the decoder never stalls).
//   Framing     HUNT takes 0xA5 (v2), and in auto mode also 0x00..0x03 / 0xFF (v1 motion / init);
//               any other byte is dropped (noise). A v2 frame with a good CRC selects v2 mode; an
//               accepted or duplicate RELEASE, or rst, returns to auto mode. LEN > MAX_PAYLOAD is
//               rejected at the LEN byte (NAK BAD_LENGTH, SEQ 0) and HUNT resumes at the next byte.
//   CHECK       the clock after a frame's last byte: CRC, TYPE, LEN for the TYPE, fields
//               (frame_fields), then SEQ against next_seq (ahead: OUT_OF_ORDER; one of the 128
//               before: duplicate, ACKed, not executed; equal: accepted, FIFO types need a free
//               slot or FIFO_FULL). The first failing rule names the NAK reason. Only an accepted
//               frame writes anything (FIFO entry, configuration, heater frame).
//   m_axis_*    FIFO write strobe: m_axis_tvalid only in a CHECK clock with m_axis_tready high;
//               m_axis_tdata (entry_pack; layout docs/architecture.md "Command-FIFO entry") is
//               defined only then. A v1 packet meeting a full FIFO is dropped (v1_overrun).
//   cfg_*, heat_*, fault_clear, release_req   an accepted CONFIG_AXIS / heater frame /
//               FAULT_CLEAR / RELEASE.
//   Soft limits  travel_guard: an accepted CONFIG_TRAVEL sets an axis's travel; a LINE,
//               LINE_PROFILE or ARC whose end (queued end + its steps) leaves the travel of an
//               enabled axis is answered NAK TRAVEL and not queued (after the SEQ rules, before
//               FIFO_FULL). The queued end follows every FIFO motion entry (v1 packets too: they
//               are never refused, v1 has no NAK) and is set to `position` on every clock of
//               `travel_resync` (the queue is flushed) and at rst.
//   hello, status_req, ack_req, nak (+ nak_seq as received, nak_reason)   answer requests.
//   motion_set  an accepted MOTION frame (unsequenced, answered by STATUS: status_req strobes
//               with it), with motion_data {flags, feed, rapid, ramp} (payload bytes 0..8; valid
//               with the strobe). Field rules: flags bits 7:3 0 and RESUME not with HOLD or
//               CANCEL, feed and rapid 1 .. 0x8000, ramp >= 1 (else NAK BAD_FIELD).
//   trig_wr, setpos_wr, trig_query (TRIGGER = 1)   an accepted TRIGGER (sequenced: fields mode
//               0..3, mask u16 non-zero with bits of axes < min(N_AXES, 8) only for HOME (1), 0 for
//               the other modes, else NAK BAD_FIELD), an accepted SET_POSITION (sequenced: LEN 2 +
//               4 N_AXES, mask non-zero with bits < N_AXES only, else BAD_FIELD; after the SEQ
//               rules NAK BUSY unless motion_quiet), a TRIGGER_QUERY (unsequenced, LEN 0); their
//               payload in ctl_data (bytes 0 .. 1 + 4 N_AXES, byte i in [8*i+:8]; valid with the
//               strobe). With TRIGGER = 0 the three types are unknown.
//   frame_ok    a v2 frame that passed every check (HELLO, STATUS_QUERY, accepted, duplicate).
//   crc_error, length_error, unknown_type   a v2 frame rejected for that reason (length_error
//               also at the LEN byte); no strobe for BAD_FIELD, OUT_OF_ORDER, FIFO_FULL, TRAVEL or
//               BUSY.
//   timeout     a started v1 packet or v2 frame with no byte for WATCHDOG_CLKS clocks (v2: also
//               NAK TIMEOUT, SEQ as received or 0 before the SEQ byte).
//   noise       a byte dropped in HUNT. v1_packet   a v1 packet written to the FIFO.
//   next_seq, v2_mode, partial   registers.
// Timing: last byte's edge L -> CHECK between L and L + 1, entry written on edge L + 1, the
//   strobes above high from L + 1 to L + 2 (noise: the clock after its byte; BAD_LENGTH at the
//   LEN byte: the clock after it; timeout: WATCHDOG_CLKS clocks after the last byte's clock).
// Build options: PROFILES, ARCS, OUTPUTS, HEATERS = 0 make LINE_PROFILE, ARC, OUTPUT, the heater
//   frames unknown types (their entry fields and heat_* constant 0); TRIGGER = 0 TRIGGER,
//   SET_POSITION and TRIGGER_QUERY.
// Requires N_AXES >= 2, MAX_PAYLOAD <= 127. rst is synchronous, active high (auto mode,
//   next_seq = 0).
`default_nettype none

`include "fpgacnc_spec.vh"

module frame_decoder #(
    parameter N_AXES        = 4,
    parameter WATCHDOG_CLKS = 5_000_000,  // 100 ms at 50 MHz
    parameter MAX_PAYLOAD   = `FPGACNC_MAX_PAYLOAD,
    parameter PROFILES      = 1,  // 0: LINE_PROFILE (0x12) is an unknown type
    parameter ARCS          = 1,  // 0: ARC (0x13) is an unknown type
    parameter OUTPUTS       = 1,  // 0: OUTPUT (0x15) is an unknown type
    parameter HEATERS       = 1,  // 0: heater frames (0x20..0x24) are unknown types
    parameter TRIGGER       = 0   // 0: TRIGGER, SET_POSITION, TRIGGER_QUERY are unknown types
) (
    input wire clk,
    input wire rst,

    input  wire [7:0] s_axis_tdata,
    input  wire       s_axis_tvalid,
    output wire       s_axis_tready,

    output wire [`FPGACNC_ENTRY_W+32*N_AXES-1:0] m_axis_tdata,
    output wire                    m_axis_tvalid,
    input  wire                    m_axis_tready,

    output wire        cfg_wr,
    output wire [ 7:0] cfg_axis,
    output wire [63:0] cfg_data,

    output wire         heat_wr,
    output wire [  7:0] heat_type,
    output wire [  7:0] heat_len,
    output wire [159:0] heat_data,

    output wire       fault_clear,
    output wire       release_req,
    output wire       hello,
    output wire       status_req,
    output wire        motion_set,
    output wire [71:0] motion_data,
    output wire        trig_wr,
    output wire        setpos_wr,
    output wire        trig_query,
    output wire [8*(2+4*N_AXES)-1:0] ctl_data,
    input  wire        motion_quiet,  // FIFO empty, nothing prepared or running (SET_POSITION)
    output wire       ack_req,
    output wire       nak,
    output wire [7:0] nak_seq,
    output wire [7:0] nak_reason,

    input wire                   travel_resync,  // the FIFO is flushed (e-stop, hard limit)
    input wire [32*N_AXES-1:0]   position,       // the position counters (axis a in [32*a+:32])

    output wire [7:0] next_seq,
    output wire       v2_mode,
    output wire       partial,     // a packet or frame has started and is not complete yet

    output wire frame_ok,
    output wire crc_error,
    output wire length_error,
    output wire unknown_type,
    output wire timeout,
    output wire noise,
    output wire v1_packet,
    output wire v1_overrun
);

  localparam ENTRY_W = `FPGACNC_ENTRY_W + 32 * N_AXES;
  // entry without the LINE_PROFILE and ARC fields
  localparam BASE_W = `FPGACNC_ENTRY_BASE_W + 32 * N_AXES;
  localparam PROF_W = `FPGACNC_ENTRY_PROF_W + 32 * N_AXES;  // entry without the ARC fields
  // payload bytes kept: LINE_PROFILE with int32 steps, ARC (63); heater frames need 20
  localparam integer PB = (28 + 4 * N_AXES > 63) ? 28 + 4 * N_AXES : 63;

  localparam [2:0] ST_HUNT = 3'd0, ST_V1 = 3'd1, ST_LEN = 3'd2, ST_SEQ = 3'd3, ST_TYPE = 3'd4,
                   ST_PAY = 3'd5, ST_CRC1 = 3'd6, ST_CRC2 = 3'd7;

  localparam [7:0] T_HELLO = `FPGACNC_T_HELLO, T_STATUS = `FPGACNC_T_STATUS_QUERY,
                   T_FCLR = `FPGACNC_T_FAULT_CLEAR, T_CFG = `FPGACNC_T_CONFIG_AXIS,
                   T_NUM = `FPGACNC_T_NUMERATORS, T_REL = `FPGACNC_T_RELEASE,
                   T_LINE = `FPGACNC_T_LINE, T_DWELL = `FPGACNC_T_DWELL,
                   T_LPROF = `FPGACNC_T_LINE_PROFILE, T_ARC = `FPGACNC_T_ARC,
                   T_OUT = `FPGACNC_T_OUTPUT, T_CTRAV = `FPGACNC_T_CONFIG_TRAVEL,
                   T_MOTION = `FPGACNC_T_MOTION;
  localparam [7:0] T_HCFG = `FPGACNC_T_HEATER_CONFIG, T_HSET = `FPGACNC_T_HEATER_SETPOINT,
                   T_HTAB = `FPGACNC_T_THERMISTOR_TABLE, T_HSAF = `FPGACNC_T_HEATER_SAFETY,
                   T_HWD = `FPGACNC_T_HEATER_WATCHDOG;

  localparam [7:0] R_BAD_CRC = `FPGACNC_NAK_BAD_CRC, R_BAD_LENGTH = `FPGACNC_NAK_BAD_LENGTH,
                   R_UNKNOWN_TYPE = `FPGACNC_NAK_UNKNOWN_TYPE, R_TIMEOUT = `FPGACNC_NAK_TIMEOUT,
                   R_OUT_OF_ORDER = `FPGACNC_NAK_OUT_OF_ORDER, R_FIFO_FULL = `FPGACNC_NAK_FIFO_FULL,
                   R_BAD_FIELD = `FPGACNC_NAK_BAD_FIELD, R_TRAVEL = `FPGACNC_NAK_TRAVEL,
                   R_BUSY = `FPGACNC_NAK_BUSY;
  localparam [7:0] T_TRIG = `FPGACNC_T_TRIGGER, T_SETPOS = `FPGACNC_T_SET_POSITION,
                   T_TQUERY = `FPGACNC_T_TRIGGER_QUERY;
  // TRIGGER HOME mask: bit a (min) and 8 + a (max) of the axes < min(N_AXES, 8)
  localparam integer NSW_I = (N_AXES > 8) ? 8 : N_AXES;
  localparam integer SWM_I = (1 << NSW_I) - 1;
  localparam [15:0] SW_MASK = {SWM_I[7:0], SWM_I[7:0]};
  localparam integer AXM_I = (1 << N_AXES) - 1;
  localparam [15:0] AX_MASK = AXM_I[15:0];  // SET_POSITION mask: axes < N_AXES
  localparam integer SPLEN_I = 2 + 4 * N_AXES;
  localparam [7:0] SPLEN = SPLEN_I[7:0];

  localparam integer MOT_RSV_I = `FPGACNC_MOTION_RESERVED;
  localparam [7:0] MOT_RSV = MOT_RSV_I[7:0];
  localparam integer RATE_ONE_I = `FPGACNC_RATE_ONE;
  localparam [15:0] RATE_ONE = RATE_ONE_I[15:0];
  localparam integer MAXP_I = MAX_PAYLOAD;
  localparam [7:0] MAXP = MAXP_I[7:0];
  localparam integer NAX_I = N_AXES;
  localparam [7:0] NAX8 = NAX_I[7:0];

  localparam WD_W = $clog2(WATCHDOG_CLKS + 1);
  localparam integer WD_LAST_I = WATCHDOG_CLKS - 1;
  localparam [WD_W-1:0] WD_LAST = WD_LAST_I[WD_W-1:0];

  reg  [       2:0] st_reg;
  reg  [       6:0] cnt_reg;  // payload bytes received (v1: bytes after the first)
  reg               is_init_reg;
  reg  [       1:0] code_reg;
  reg  [       7:0] len_reg;
  reg  [       7:0] seq_reg;
  reg  [       7:0] type_reg;
  reg  [    8*PB-1:0] pay_reg;  // payload byte i in [8*i+:8]
  reg  [  WD_W-1:0] idle_reg;
  reg               chk_reg;  // CHECK clock
  reg               chk_v1_reg;  // ... of a v1 packet (else of a v2 frame)
  reg               v2_mode_reg;
  reg  [       7:0] next_seq_reg;

  reg cfg_wr_reg, heat_wr_reg, fault_clear_reg, release_reg, hello_reg, status_reg, ack_reg, nak_reg;
  reg motion_reg, trig_wr_reg, setpos_wr_reg, trig_query_reg;
  reg [7:0] nak_seq_reg, nak_reason_reg;
  reg frame_ok_reg, crc_error_reg, length_error_reg, unknown_type_reg, timeout_reg, noise_reg;
  reg v1_packet_reg, v1_overrun_reg;

  wire        take = s_axis_tvalid;
  wire [ 7:0] d = s_axis_tdata;
  wire        in_frame = (st_reg >= ST_LEN);
  wire [15:0] crc;

  crc16_ccitt u_crc (
      .clk (clk),
      .rst (rst),
      .init(st_reg == ST_LEN),
      .en  (take && in_frame),
      .data(d),
      .crc (crc)
  );

  // ---------------------------------------------------------------- payload fields
  // Payload byte i (reads pay_reg directly: a simulator need not copy the whole payload register
  // for every field).
  function [7:0] pb;
    input integer i;
    begin
      pb = pay_reg[8*i+:8];
    end
  endfunction

  // ---------------------------------------------------------------- CHECK
  wire t_hello = (type_reg == T_HELLO);
  wire t_status = (type_reg == T_STATUS);
  wire t_fclr = (type_reg == T_FCLR);
  wire t_cfg = (type_reg == T_CFG);
  wire t_num = (type_reg == T_NUM);
  wire t_rel = (type_reg == T_REL);
  wire t_line = (type_reg == T_LINE);
  wire t_dwell = (type_reg == T_DWELL);
  wire t_ctrav = (type_reg == T_CTRAV);
  wire t_motion = (type_reg == T_MOTION);
  wire t_trig = (TRIGGER != 0) && (type_reg == T_TRIG);
  wire t_setpos = (TRIGGER != 0) && (type_reg == T_SETPOS);
  wire t_tquery = (TRIGGER != 0) && (type_reg == T_TQUERY);
  // ---- heater frames
  wire t_hcfg = (type_reg == T_HCFG);
  wire t_hset = (type_reg == T_HSET);
  wire t_htab = (type_reg == T_HTAB);
  wire t_hsaf = (type_reg == T_HSAF);
  wire t_hwd = (type_reg == T_HWD);
  wire t_heat = (HEATERS != 0) && (t_hcfg || t_hset || t_htab || t_hsaf || t_hwd);
  wire t_lprof = (PROFILES != 0) && (type_reg == T_LPROF);
  wire t_arc = (ARCS != 0) && (type_reg == T_ARC);
  wire t_out = (OUTPUTS != 0) && (type_reg == T_OUT);
  // TYPE and LEN rules, formed (block-local regs) and registered on the edge that takes the
  // frame's last byte, as the field rules are: LEN, TYPE and the flag byte are complete then and
  // stay until the CHECK clock, the only clock that reads them.
  reg known_reg, len_ok_reg, ctrav_ok_reg, motion_ok_reg, trig_ok_reg, setpos_ok_reg;
  always @(posedge clk) begin : len_rules
    reg short_steps, line_len_ok, prof_len_ok, heat_len_ok;
    reg [7:0] len_m6, len_m28;
    if (rst) begin
      known_reg    <= 1'b0;
      len_ok_reg   <= 1'b0;
      ctrav_ok_reg <= 1'b0;
      motion_ok_reg <= 1'b0;
      trig_ok_reg   <= 1'b0;
      setpos_ok_reg <= 1'b0;
    end else if (take && st_reg == ST_CRC2) begin
      // TRIGGER: mode 0..3; HOME (1): mask non-zero, switches of axes < min(N_AXES, 8) only;
      // other modes: mask 0
      trig_ok_reg <= pb(0) <= 8'd3 &&
                     ((pb(0) == 8'd1) ? ({pb(1), pb(2)} != 16'd0 &&
                                         ({pb(1), pb(2)} & ~SW_MASK) == 16'd0)
                                      : {pb(1), pb(2)} == 16'd0);
      // SET_POSITION: mask non-zero, axes < N_AXES only
      setpos_ok_reg <= {pb(0), pb(1)} != 16'd0 && ({pb(0), pb(1)} & ~AX_MASK) == 16'd0;
      // CONFIG_TRAVEL: axis < N_AXES, flag bits 7:1 0, and MIN <= MAX when enabled
      ctrav_ok_reg <= pb(0) < NAX8 && pay_reg[15:9] == 7'd0 &&
                      (!pay_reg[8] || $signed(be32p(2)) <= $signed(be32p(6)));
      // MOTION: flags bits 7:2 0, not HOLD and RESUME together; feed and rapid 1 .. 0x8000;
      // ramp >= 1
      motion_ok_reg <= (pay_reg[7:0] & MOT_RSV) == 8'd0 && pay_reg[1:0] != 2'b11 &&
                       pay_reg[2:1] != 2'b11 &&
                       {pb(1), pb(2)} != 16'd0 && {pb(1), pb(2)} <= RATE_ONE &&
                       {pb(3), pb(4)} != 16'd0 && {pb(3), pb(4)} <= RATE_ONE &&
                       be32p(5) != 32'd0;
      short_steps = pay_reg[7];  // flag bit 7: int16 step fields
      len_m6 = len_reg - 8'd6;
      line_len_ok = (len_reg >= `FPGACNC_LEN_LINE_HEADER) &&
                    (short_steps ? (len_m6[0] == 1'b0 && {1'b0, len_m6[7:1]} <= NAX8)
                                 : (len_m6[1:0] == 2'b00 && {2'b00, len_m6[7:2]} <= NAX8));
      // LINE_PROFILE: the same step fields from byte 28
      len_m28 = len_reg - 8'd28;
      prof_len_ok = (len_reg >= `FPGACNC_LEN_LINE_PROFILE_HEADER) &&
                    (short_steps ? (len_m28[0] == 1'b0 && {1'b0, len_m28[7:1]} <= NAX8)
                                 : (len_m28[1:0] == 2'b00 && {2'b00, len_m28[7:2]} <= NAX8));
      heat_len_ok = t_heat && ((t_hcfg && len_reg == `FPGACNC_LEN_HEATER_CONFIG) ||
                    (t_hset && len_reg == `FPGACNC_LEN_HEATER_SETPOINT) ||
                    (t_htab && len_reg >= `FPGACNC_LEN_THERMISTOR_TABLE_MIN &&
                     len_reg <= `FPGACNC_LEN_THERMISTOR_TABLE_MAX && !len_reg[0]) ||
                    (t_hsaf && len_reg == `FPGACNC_LEN_HEATER_SAFETY) ||
                    (t_hwd && len_reg == `FPGACNC_LEN_HEATER_WATCHDOG));
      known_reg <= t_hello || t_status || t_fclr || t_cfg || t_num || t_rel || t_line || t_dwell ||
               t_lprof || t_arc || t_out || t_heat || t_ctrav || t_motion || t_trig || t_setpos ||
               t_tquery;
      len_ok_reg <= ((t_hello || t_status || t_fclr || t_rel || t_tquery) && len_reg == 8'd0) ||
                (t_trig && len_reg == `FPGACNC_LEN_TRIGGER) || (t_setpos && len_reg == SPLEN) ||
                (t_cfg && len_reg == `FPGACNC_LEN_CONFIG_AXIS) ||
                (t_ctrav && len_reg == `FPGACNC_LEN_CONFIG_TRAVEL) ||
                (t_motion && len_reg == `FPGACNC_LEN_MOTION) ||
                (t_num && len_reg == `FPGACNC_LEN_NUMERATORS) ||
                (t_dwell && len_reg == `FPGACNC_LEN_DWELL) || (t_line && line_len_ok) ||
                (t_lprof && prof_len_ok) || (t_arc && len_reg == `FPGACNC_LEN_ARC) ||
                (t_out && len_reg == `FPGACNC_LEN_OUTPUT) || heat_len_ok;
    end
  end
  // The field rules (frame_fields) are evaluated on the edge that takes the frame's last byte:
  // payload, LEN and TYPE are complete then and stay until the CHECK clock, so field_ok holds the
  // rules of the frame being checked.
  wire field_ok_f;
  wire field_ok = field_ok_f && (!t_ctrav || ctrav_ok_reg) && (!t_motion || motion_ok_reg) &&
                  (!t_trig || trig_ok_reg) && (!t_setpos || setpos_ok_reg);
  frame_fields #(
      .N_AXES(N_AXES),
      .PB    (PB)
  ) u_fields (
      .clk    (clk),
      .rst    (rst),
      .en     (take && st_reg == ST_CRC2),
      .pay    (pay_reg),
      .len    (len_reg),
      .t_line (t_line),
      .t_cfg  (t_cfg),
      .t_lprof(t_lprof),
      .t_arc  (t_arc),
      .t_out  (t_out),
      .t_heat (t_heat),
      .t_hcfg (t_hcfg),
      .t_htab (t_htab),
      .t_hsaf (t_hsaf),
      .t_hwd  (t_hwd),
      .ok     (field_ok_f)
  );
  wire sequenced = t_fclr || t_cfg || t_num || t_rel || t_line || t_dwell || t_lprof || t_arc ||
                   t_out || t_heat || t_ctrav || t_trig || t_setpos;
  wire to_fifo = t_num || t_line || t_dwell || t_lprof || t_arc || t_out;
  wire [7:0] seq_diff = seq_reg - next_seq_reg;
  wire seq_new = (seq_diff == 8'd0);
  wire seq_dup = seq_diff[7];  // next_seq - 128 .. next_seq - 1

  wire v2_chk = chk_reg && !chk_v1_reg;
  wire moves = t_line || t_lprof || t_arc;  // the frames travel_guard checks
  wire travel_ok;
  wire v2_accept = v2_chk && (crc == 16'd0) && known_reg && len_ok_reg && field_ok && sequenced && seq_new &&
                   (!moves || travel_ok) && (!t_setpos || motion_quiet) &&
                   (!to_fifo || m_axis_tready);
  wire v1_write = chk_reg && chk_v1_reg && m_axis_tready;

  // The FIFO entry (entry_pack), packed in the CHECK clock only (don't-care in other clocks: the
  // FIFO takes it only with m_axis_tvalid, which is high only in a CHECK clock).
  wire [ENTRY_W-1:0] entry;
  entry_pack #(
      .N_AXES (N_AXES),
      .PB     (PB),
      .ENTRY_W(ENTRY_W),
      .BASE_W (BASE_W),
      .PROF_W (PROF_W)
  ) u_pack (
      .build  (chk_reg),
      .v1     (chk_v1_reg),
      .is_init(is_init_reg),
      .code   (code_reg),
      .t_line (t_line),
      .t_dwell(t_dwell),
      .t_lprof(t_lprof),
      .t_arc  (t_arc),
      .t_out  (t_out),
      .len    (len_reg),
      .pay    (pay_reg),
      .entry  (entry)
  );

  // Payload bytes, written as they are taken (v1 packet, v2 payload): the next value is formed in
  // the branch that writes it, so the register is updated in place and skipped between bytes.
  always @(posedge clk) begin : pay_wr
    reg [8*PB-1:0] pay_n;
    integer k;
    if (rst) begin
      pay_reg <= {8 * PB{1'b0}};
    end else if (take && (st_reg == ST_V1 || st_reg == ST_PAY)) begin
      pay_n = pay_reg;
      for (k = 0; k < PB; k = k + 1) if (cnt_reg == k[6:0]) pay_n[8*k+:8] = d;
      pay_reg <= pay_n;
    end
  end

  // ---------------------------------------------------------------- byte handling and strobes
  always @(posedge clk) begin
    cfg_wr_reg       <= 1'b0;
    heat_wr_reg      <= 1'b0;
    fault_clear_reg  <= 1'b0;
    release_reg      <= 1'b0;
    hello_reg        <= 1'b0;
    status_reg       <= 1'b0;
    motion_reg       <= 1'b0;
    trig_wr_reg      <= 1'b0;
    setpos_wr_reg    <= 1'b0;
    trig_query_reg   <= 1'b0;
    ack_reg          <= 1'b0;
    nak_reg          <= 1'b0;
    frame_ok_reg     <= 1'b0;
    crc_error_reg    <= 1'b0;
    length_error_reg <= 1'b0;
    unknown_type_reg <= 1'b0;
    timeout_reg      <= 1'b0;
    noise_reg        <= 1'b0;
    v1_packet_reg    <= 1'b0;
    v1_overrun_reg   <= 1'b0;
    chk_reg          <= 1'b0;

    // CHECK of the packet/frame completed on the previous edge.
    if (chk_reg) begin
      if (chk_v1_reg) begin
        v1_packet_reg  <= m_axis_tready;
        v1_overrun_reg <= !m_axis_tready;
      end else if (crc != 16'd0) begin
        nak_reg        <= 1'b1;
        nak_reason_reg <= R_BAD_CRC;
        nak_seq_reg    <= seq_reg;
        crc_error_reg  <= 1'b1;
      end else begin
        v2_mode_reg <= 1'b1;
        if (!known_reg || !len_ok_reg || !field_ok) begin
          nak_reg          <= 1'b1;
          nak_seq_reg      <= seq_reg;
          nak_reason_reg   <= !known_reg ? R_UNKNOWN_TYPE : !len_ok_reg ? R_BAD_LENGTH : R_BAD_FIELD;
          unknown_type_reg <= !known_reg;
          length_error_reg <= known_reg && !len_ok_reg;
        end else if (!sequenced) begin
          frame_ok_reg <= 1'b1;
          hello_reg    <= t_hello;
          status_reg   <= t_status || t_motion;
          motion_reg   <= t_motion;
          trig_query_reg <= t_tquery;
        end else if (!seq_new && !seq_dup) begin
          nak_reg        <= 1'b1;
          nak_seq_reg    <= seq_reg;
          nak_reason_reg <= R_OUT_OF_ORDER;
        end else if (seq_dup) begin
          frame_ok_reg <= 1'b1;
          ack_reg      <= 1'b1;
          if (t_rel) v2_mode_reg <= 1'b0;
        end else if (moves && !travel_ok) begin
          nak_reg        <= 1'b1;
          nak_seq_reg    <= seq_reg;
          nak_reason_reg <= R_TRAVEL;
        end else if (t_setpos && !motion_quiet) begin
          nak_reg        <= 1'b1;
          nak_seq_reg    <= seq_reg;
          nak_reason_reg <= R_BUSY;
        end else if (to_fifo && !m_axis_tready) begin
          nak_reg        <= 1'b1;
          nak_seq_reg    <= seq_reg;
          nak_reason_reg <= R_FIFO_FULL;
        end else begin
          frame_ok_reg    <= 1'b1;
          ack_reg         <= 1'b1;
          next_seq_reg    <= next_seq_reg + 8'd1;
          cfg_wr_reg      <= t_cfg;
          heat_wr_reg     <= t_heat;
          fault_clear_reg <= t_fclr;
          release_reg     <= t_rel;
          trig_wr_reg     <= t_trig;
          setpos_wr_reg   <= t_setpos;
          if (t_rel) v2_mode_reg <= 1'b0;
        end
      end
    end

    if (take) begin
      idle_reg <= {WD_W{1'b0}};
      case (st_reg)
        ST_HUNT: begin
          cnt_reg     <= 7'd0;
          is_init_reg <= (d == `FPGACNC_V1_INIT_BYTE);
          code_reg    <= d[1:0];
          if (d == `FPGACNC_SYNC) st_reg <= ST_LEN;
          else if (!v2_mode_reg && (d == `FPGACNC_V1_INIT_BYTE || d[7:2] == 6'd0)) st_reg <= ST_V1;
          else noise_reg <= 1'b1;
        end
        ST_V1: begin
          cnt_reg <= cnt_reg + 7'd1;
          if (cnt_reg == (is_init_reg ? 7'd7 : 7'd9)) begin
            st_reg     <= ST_HUNT;
            chk_reg    <= 1'b1;
            chk_v1_reg <= 1'b1;
          end
        end
        ST_LEN: begin
          len_reg <= d;
          if (d > MAXP) begin
            st_reg           <= ST_HUNT;
            nak_reg          <= 1'b1;
            nak_seq_reg      <= 8'd0;
            nak_reason_reg   <= R_BAD_LENGTH;
            length_error_reg <= 1'b1;
          end else begin
            st_reg <= ST_SEQ;
          end
        end
        ST_SEQ: begin
          seq_reg <= d;
          st_reg  <= ST_TYPE;
        end
        ST_TYPE: begin
          type_reg <= d;
          cnt_reg  <= 7'd0;
          st_reg   <= (len_reg == 8'd0) ? ST_CRC1 : ST_PAY;
        end
        ST_PAY: begin
          cnt_reg <= cnt_reg + 7'd1;
          if ({1'b0, cnt_reg} == len_reg - 8'd1) st_reg <= ST_CRC1;
        end
        ST_CRC1: st_reg <= ST_CRC2;
        default: begin  // ST_CRC2
          st_reg     <= ST_HUNT;
          chk_reg    <= 1'b1;
          chk_v1_reg <= 1'b0;
        end
      endcase
    end else if (st_reg != ST_HUNT) begin
      if (idle_reg == WD_LAST) begin
        st_reg      <= ST_HUNT;
        idle_reg    <= {WD_W{1'b0}};
        timeout_reg <= 1'b1;
        if (in_frame) begin
          nak_reg        <= 1'b1;
          nak_seq_reg    <= (st_reg >= ST_TYPE) ? seq_reg : 8'd0;
          nak_reason_reg <= R_TIMEOUT;
        end
      end else begin
        idle_reg <= idle_reg + {{(WD_W - 1) {1'b0}}, 1'b1};
      end
    end

    if (rst) begin
      st_reg           <= ST_HUNT;
      cnt_reg          <= 7'd0;
      is_init_reg      <= 1'b0;
      code_reg         <= 2'd0;
      len_reg          <= 8'd0;
      seq_reg          <= 8'd0;
      type_reg         <= 8'd0;
      idle_reg         <= {WD_W{1'b0}};
      chk_reg          <= 1'b0;
      chk_v1_reg       <= 1'b0;
      v2_mode_reg      <= 1'b0;
      next_seq_reg     <= 8'd0;
      cfg_wr_reg       <= 1'b0;
      heat_wr_reg      <= 1'b0;
      fault_clear_reg  <= 1'b0;
      release_reg      <= 1'b0;
      hello_reg        <= 1'b0;
      status_reg       <= 1'b0;
      motion_reg       <= 1'b0;
      trig_wr_reg      <= 1'b0;
      setpos_wr_reg    <= 1'b0;
      trig_query_reg   <= 1'b0;
      ack_reg          <= 1'b0;
      nak_reg          <= 1'b0;
      nak_seq_reg      <= 8'd0;
      nak_reason_reg   <= 8'd0;
      frame_ok_reg     <= 1'b0;
      crc_error_reg    <= 1'b0;
      length_error_reg <= 1'b0;
      unknown_type_reg <= 1'b0;
      timeout_reg      <= 1'b0;
      noise_reg        <= 1'b0;
      v1_packet_reg    <= 1'b0;
      v1_overrun_reg   <= 1'b0;
    end
  end

  // CONFIG_AXIS fields of the frame accepted on the last CHECK edge (payload registers are not
  // written again before the next frame's fifth byte).
  reg [7:0] cfg_axis_reg;
  reg [63:0] cfg_data_reg;
  reg [7:0] heat_type_reg, heat_len_reg;
  reg [159:0] heat_data_reg;
  always @(posedge clk) begin
    if (v2_chk) begin
      heat_type_reg <= type_reg;
      heat_len_reg  <= len_reg;
      heat_data_reg <= pay_reg[159:0];
      cfg_axis_reg <= pb(0);
      cfg_data_reg <= {pb(1), pb(2), pb(3), pb(4),
                       pb(5), pb(6), pb(7), pb(8)};
    end
  end

  // ---------------------------------------------------------------- soft limits
  // trav_delta_reg: the steps of the frame being received, formed on the edge that takes its
  // first CRC byte (the payload is complete then; the check reads them on the next byte's edge),
  // or of a v1 packet in its CHECK clock (the queued end follows it on the next edge): LINE from
  // byte 6, LINE_PROFILE from byte 28 (int16 with flag bit 7, else int32; axes beyond LEN 0),
  // ARC's DX, DY (int24) and DZ (int32) on the axes of its plane, v1 motion X and Y at bytes 0
  // and 4; 0 for anything else.
  function [31:0] be32p;
    input integer i;
    begin
      be32p = {pay_reg[8*i+:8], pay_reg[8*(i+1)+:8], pay_reg[8*(i+2)+:8], pay_reg[8*(i+3)+:8]};
    end
  endfunction
  function [31:0] be24s;  // the big-endian int24 at byte i, sign-extended
    input integer i;
    begin
      be24s = {{8{pay_reg[8*i+7]}}, pay_reg[8*i+:8], pay_reg[8*(i+1)+:8], pay_reg[8*(i+2)+:8]};
    end
  endfunction
  localparam TW = 32 * ((N_AXES < 3) ? 3 : N_AXES);  // X, Y, Z at least (an ARC's axes)
  reg [32*N_AXES-1:0] trav_delta_reg;
  always @(posedge clk) begin : travel_delta
    reg [31:0] du, dv, dh;
    /* verilator lint_off UNUSEDSIGNAL */
    reg [TW-1:0] wide;  // Z of an ARC unused with 2 axes
    /* verilator lint_on UNUSEDSIGNAL */
    integer a;
    if ((take && st_reg == ST_CRC1) || (chk_reg && chk_v1_reg)) begin
      wide = {TW{1'b0}};
      du   = be24s(8);
      dv   = be24s(11);
      dh   = be32p(14);
      if (chk_reg && chk_v1_reg) begin
        if (!is_init_reg) wide[63:0] = {be32p(4), be32p(0)};
      end else if (t_line || t_lprof) begin
        // constant offsets only (LINE from byte 6, LINE_PROFILE from byte 28)
        for (a = 0; a < N_AXES; a = a + 1) begin
          if (pay_reg[7]) begin
            if ({1'b0, len_reg} >= (t_line ? 9'd8 : 9'd30) + 9'd2 * a[8:0])
              wide[32*a+:32] = t_line ? {{16{pay_reg[8*(6+2*a)+7]}}, pay_reg[8*(6+2*a)+:8],
                                         pay_reg[8*(7+2*a)+:8]}
                                      : {{16{pay_reg[8*(28+2*a)+7]}}, pay_reg[8*(28+2*a)+:8],
                                         pay_reg[8*(29+2*a)+:8]};
          end else if ({1'b0, len_reg} >= (t_line ? 9'd10 : 9'd32) + 9'd4 * a[8:0]) begin
            wide[32*a+:32] = t_line ? be32p(6 + 4 * a) : be32p(28 + 4 * a);
          end
        end
      end else if (t_arc) begin
        // planes (flags bits 3:2): XY u=X v=Y h=Z; ZX u=Z v=X h=Y; YZ u=Y v=Z h=X
        case (pay_reg[3:2])
          2'd0: wide[95:0] = {dh, dv, du};
          2'd1: wide[95:0] = {du, dh, dv};
          default: wide[95:0] = {dv, du, dh};
        endcase
      end
      trav_delta_reg <= wide[32*N_AXES-1:0];
    end
    if (rst) trav_delta_reg <= {32 * N_AXES{1'b0}};
  end

  travel_guard #(
      .N_AXES(N_AXES)
  ) u_travel (
      .clk     (clk),
      .rst     (rst),
      .cfg_wr  (v2_accept && t_ctrav),
      .cfg_axis(pay_reg[3:0] | {4{pay_reg[7:4] != 4'd0}}),  // axis >= 16: none
      .cfg_en  (pay_reg[8]),
      .cfg_min (be32p(2)),
      .cfg_max (be32p(6)),
      .check   (take && st_reg == ST_CRC2),
      .delta   (trav_delta_reg),
      .accept  ((v2_accept && moves) || v1_packet_reg),
      .resync  (travel_resync),
      .pos     (position),
      .ok      (travel_ok)
  );

  assign s_axis_tready = 1'b1;
  assign m_axis_tdata  = entry;
  assign m_axis_tvalid = v1_write || (v2_accept && to_fifo);
  assign cfg_wr        = cfg_wr_reg;
  assign cfg_axis      = cfg_axis_reg;
  assign cfg_data      = cfg_data_reg;
  assign heat_wr       = heat_wr_reg;
  assign heat_type     = heat_type_reg;
  assign heat_len      = heat_len_reg;
  assign heat_data     = heat_data_reg;
  assign fault_clear   = fault_clear_reg;
  assign release_req   = release_reg;
  assign hello         = hello_reg;
  assign status_req    = status_reg;
  assign motion_set    = motion_reg;
  assign motion_data   = pay_reg[71:0];
  assign trig_wr       = trig_wr_reg;
  assign setpos_wr     = setpos_wr_reg;
  assign trig_query    = trig_query_reg;
  assign ctl_data      = pay_reg[8*(2+4*N_AXES)-1:0];
  assign ack_req       = ack_reg;
  assign nak           = nak_reg;
  assign nak_seq       = nak_seq_reg;
  assign nak_reason    = nak_reason_reg;
  assign next_seq      = next_seq_reg;
  assign v2_mode       = v2_mode_reg;
  assign partial       = (st_reg != ST_HUNT);
  assign frame_ok      = frame_ok_reg;
  assign crc_error     = crc_error_reg;
  assign length_error  = length_error_reg;
  assign unknown_type  = unknown_type_reg;
  assign timeout       = timeout_reg;
  assign noise         = noise_reg;
  assign v1_packet     = v1_packet_reg;
  assign v1_overrun    = v1_overrun_reg;

`ifdef FORMAL
`ifdef FORMAL_V2
  // Formal properties of the v2 path (scripts/formal/frame_decoder_v2.ys, k-induction): any byte
  // stream. An independent monitor follows each frame from the 0xA5 the decoder takes as a sync
  // byte and computes CRC-16/CCITT-FALSE bit by bit over the bytes after it. Whenever the decoder
  // accepts a v2 frame (FIFO write, configuration write, any sequenced action: v2_accept), that
  // frame was complete (LEN + 5 bytes after the sync: LEN, SEQ, TYPE, payload, CRC) and its CRC
  // checked (the CRC over LEN..payload equals the two CRC bytes: the residue over all of them is 0).
  // So no segment or configuration comes from a frame with a bad CRC or from a partial frame.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  function [15:0] f_crc_bits;  // bit-serial LFSR form of the CRC (MSB first)
    input [15:0] c;
    input [7:0] b;
    integer k;
    reg [15:0] x;
    reg fb;
    begin
      x = c;
      for (k = 7; k >= 0; k = k - 1) begin
        fb = x[15] ^ b[k];
        x  = {x[14:0], 1'b0} ^ (fb ? 16'h1021 : 16'h0000);
      end
      f_crc_bits = x;
    end
  endfunction

  reg        f_in_reg;   // a frame has started (its sync byte was taken) and not been abandoned
  reg [ 7:0] f_n_reg;    // bytes taken after the sync byte
  reg [ 7:0] f_len_reg;  // the first of them (LEN)
  reg [15:0] f_crc_reg;  // CRC over the bytes after the sync
  wire       f_sync = take && (st_reg == ST_HUNT) && (d == `FPGACNC_SYNC);

  always @(posedge clk) begin
    if (f_sync) begin
      f_in_reg  <= 1'b1;
      f_n_reg   <= 8'd0;
      f_crc_reg <= 16'hFFFF;
    end else begin
      if (st_reg == ST_HUNT && !chk_reg) f_in_reg <= 1'b0;
      if (take && in_frame) begin
        f_n_reg   <= f_n_reg + 8'd1;
        f_crc_reg <= f_crc_bits(f_crc_reg, d);
        if (st_reg == ST_LEN) f_len_reg <= d;
      end
    end
    if (rst) begin
      f_in_reg <= 1'b0;
      f_n_reg  <= 8'd0;
    end
  end

  always @(*)
    if (f_past_valid && !rst) begin
      if (v2_accept) begin
        assert (f_in_reg && f_n_reg == f_len_reg + 8'd5);
        assert (f_crc_reg == 16'h0000);
      end
      if (m_axis_tvalid && !chk_v1_reg) assert (v2_accept);
      // Induction invariants: the monitor follows the decoder's frame state.
      if (in_frame) assert (f_in_reg);
      if (v2_chk) assert (f_in_reg && f_n_reg == f_len_reg + 8'd5 && f_crc_reg == crc);
      if (in_frame && st_reg != ST_LEN) assert (f_crc_reg == crc && f_len_reg == len_reg);
      if (st_reg == ST_LEN) assert (f_n_reg == 8'd0 && f_crc_reg == 16'hFFFF);
      if (st_reg == ST_SEQ) assert (f_n_reg == 8'd1);
      if (st_reg == ST_TYPE) assert (f_n_reg == 8'd2);
      if (st_reg == ST_PAY) assert (f_n_reg == 8'd3 + {1'b0, cnt_reg} && {1'b0, cnt_reg} < len_reg);
      if (st_reg == ST_CRC1) assert (f_n_reg == len_reg + 8'd3);
      if (st_reg == ST_CRC2) assert (f_n_reg == len_reg + 8'd4);
      if (in_frame && st_reg != ST_LEN) assert (len_reg <= MAXP);
    end
`else
  // Formal properties of the v1 path (scripts/formal.sh, k-induction with a small WATCHDOG_CLKS
  // override). The input never carries 0xA5 (assumed), so the decoder stays in auto mode and
  // only v1 packets and noise occur. An independent monitor counts the bytes since the last
  // packet boundary the decoder reported (CHECK of a v1 packet, or timeout) and the idle clocks
  // since the last byte.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);
  always @(*) if (s_axis_tvalid) assume (s_axis_tdata != `FPGACNC_SYNC);

  localparam integer F_W = WD_W + 1;
  localparam [F_W-1:0] F_WD = WATCHDOG_CLKS;

  reg  [    3:0] f_n;     // bytes of the current packet, including those of a packet just ended
  reg            f_init;  // the current packet's first byte was 0xFF
  reg  [F_W-1:0] f_idle;  // clocks without a byte since the last byte, saturating at WATCHDOG+1
  wire           f_boundary = chk_reg || timeout_reg;
  wire [    3:0] f_n_eff = f_boundary ? 4'd0 : f_n;  // bytes of the packet still open
  wire [    3:0] f_len = f_init ? 4'd9 : 4'd11;
  wire           f_v1_start = (s_axis_tdata == `FPGACNC_V1_INIT_BYTE) || (s_axis_tdata[7:2] == 6'd0);

  always @(posedge clk) begin
    if (take) begin
      f_idle <= {F_W{1'b0}};
      if (f_n_eff == 4'd0) begin
        f_n    <= f_v1_start ? 4'd1 : 4'd0;  // anything else is noise
        f_init <= (s_axis_tdata == `FPGACNC_V1_INIT_BYTE);
      end else begin
        f_n <= f_n_eff + 4'd1;
      end
    end else begin
      f_n <= f_n_eff;
      if (f_idle <= F_WD) f_idle <= f_idle + {{(F_W - 1) {1'b0}}, 1'b1};
    end
    if (rst) begin
      f_n    <= 4'd0;
      f_init <= 1'b0;
      f_idle <= {F_W{1'b0}};
    end
  end

  always @(*)
    if (f_past_valid && !rst) begin
      // Only v1: no frame state, auto mode, every CHECK is a v1 packet's.
      assert (st_reg == ST_HUNT || st_reg == ST_V1);
      assert (!v2_mode_reg);
      if (chk_reg) assert (chk_v1_reg);
      // An entry (FIFO write, or the overrun drop of a complete packet) only after exactly the
      // packet's length in bytes: 9 for init (first byte 0xFF), 11 for motion.
      if (chk_reg) assert (f_n == f_len);
      assert (m_axis_tvalid == (chk_reg && m_axis_tready));
      assert (!(chk_reg && timeout_reg));
      assert (!(v1_packet_reg && v1_overrun_reg));
      // Never more bytes than the packet's length.
      assert (f_n <= f_len);
      // The watchdog drops only a partial packet, and only after exactly WATCHDOG_CLKS clocks
      // without a byte ...
      if (timeout_reg) assert (f_n != 4'd0 && f_n < f_len && f_idle == F_WD);
      // ... and always then.
      if (f_n != 4'd0 && !chk_reg && f_idle == F_WD) assert (timeout_reg);
      if (f_n_eff != 4'd0) assert (f_idle < F_WD);
      // Induction invariants: the decoder's counters match the monitor.
      assert ((st_reg == ST_V1) == (f_n_eff != 4'd0));
      if (st_reg == ST_V1)
        assert (cnt_reg == {3'd0, f_n_eff - 4'd1} && is_init_reg == f_init &&
                idle_reg == f_idle[WD_W-1:0]);
      else assert (idle_reg == {WD_W{1'b0}});
      assert (f_idle <= F_WD + 1);
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !rst) begin
      // The strobes of a v1 packet follow its CHECK clock, as the FIFO's tready then said.
      assert (v1_packet_reg == ($past(chk_reg) && $past(m_axis_tready)));
      assert (v1_overrun_reg == ($past(chk_reg) && !$past(m_axis_tready)));
    end
`endif  // FORMAL_V2
`endif

endmodule

`default_nettype wire
