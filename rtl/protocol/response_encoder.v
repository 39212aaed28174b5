// response_encoder: the device's answers as a byte stream for uart_tx: v2 ACK, NAK, DONE, STATUS,
// IDENT, TRIGGER_REPORT frames with their CRC, and protocol v1's 0xAA (payloads: docs/protocol.md "Device to
// host"; generated layout constants from fpgacnc_spec.vh).
//
// Contract
//   ident_req, status_req, trig_req, nak_req (+ nak_seq, nak_reason), ack_req, done_evt, v1_ack
//               1-clock request strobes, any clock. One pending flag per frame kind, no queue: a
//               request while its flag is set merges with it (a NAK keeps the latest seq and
//               reason). A request on the clock a frame of its kind starts stays pending.
//   Order       when nothing is being sent: first every counted 0xAA (v1_ack adds one, up to 255),
//               then the highest pending kind of IDENT, STATUS, TRIGGER_REPORT, NAK, ACK, DONE. Starting an ACK
//               also clears a pending DONE (same fields).
//   next_seq .. trig_pos   live state (limits: STATUS bytes 27 + 4 N_AXES .. + 2; trig_state:
//               TRIGGER_REPORT bytes 0..3, trig_pos its positions, axis a in [32*a+:32]); all fields of a frame are snapshotted in one clock,
//               the clock before its 0xA5 is offered; frame_start is high in the clock after it.
//   Device SEQ  0 after rst, +1 (mod 256) after each v2 frame's last CRC byte is taken.
//   HEAT_BYTES  heater bytes appended to STATUS (the top bytes of heat_status; 0: none).
//   m_axis_*    tdata / tvalid from registers only, held until taken.
// Timing: request sampled on edge E -> snapshot on edge E + 1 when idle, 0xA5 offered from E + 1,
//   taken by an idle uart_tx on edge E + 2. The CRC (crc16_ccitt) is formed while the bytes go out.
// rst is synchronous, active high (nothing pending, device SEQ 0).
`default_nettype none
`include "fpgacnc_spec.vh"

module response_encoder #(
    parameter N_AXES      = `FPGACNC_DEF_N_AXES,
    parameter FIFO_DEPTH  = `FPGACNC_DEF_FIFO_DEPTH,
    parameter CLK_HZ      = `FPGACNC_DEF_CLK_HZ,
    parameter BAUD        = `FPGACNC_DEF_BAUD,
    parameter BUILD_ID    = `FPGACNC_BUILD_ID,
    parameter MAX_PAYLOAD = `FPGACNC_MAX_PAYLOAD,
    parameter HEAT_BYTES  = 0  // heater status bytes appended to STATUS (0..16)
) (
    input wire clk,
    input wire rst,

    input wire       ident_req,
    input wire       status_req,
    input wire       trig_req,
    input wire       nak_req,
    input wire [7:0] nak_seq,
    input wire [7:0] nak_reason,
    input wire       ack_req,
    input wire       done_evt,
    input wire       v1_ack,

    input wire [         7:0] next_seq,
    input wire [        15:0] fifo_free,
    input wire [        15:0] fifo_level,
    input wire [        31:0] segments_done,
    input wire [         7:0] state,
    input wire [         7:0] faults,
    input wire [32*N_AXES-1:0] position,
    input wire [   16*9-1:0] counters,
    input wire [        23:0] limits,  // limit byte, then the switch states u16 (docs/protocol.md)
    /* verilator lint_off UNUSEDSIGNAL */
    input wire [127:0] heat_status,  // its top HEAT_BYTES bytes are sent
    /* verilator lint_on UNUSEDSIGNAL */
    input wire [          31:0] trig_state,  // mode, flags, fired u16
    input wire [32*N_AXES-1:0] trig_pos,     // latched positions

    output wire [7:0] m_axis_tdata,
    output wire       m_axis_tvalid,
    input  wire       m_axis_tready,

    output wire frame_start  // 1-clock strobe: a frame's fields were snapshotted
);

  localparam integer STATUS_BASE = `FPGACNC_LENI_STATUS_HEADER +
                                   `FPGACNC_LENI_STATUS_PER_AXIS * N_AXES;
  localparam integer STATUS_LEN = STATUS_BASE + HEAT_BYTES;
  localparam integer MAX_LEN = (STATUS_LEN > `FPGACNC_LENI_IDENT) ? STATUS_LEN
                                                                  : `FPGACNC_LENI_IDENT;
  localparam integer SHB = 3 + MAX_LEN;  // LEN, SEQ, TYPE, payload
  localparam integer SHW = 8 * SHB;

  localparam integer NAX_I = N_AXES;
  localparam integer DEPTH_I = FIFO_DEPTH;
  localparam integer CLK_I = CLK_HZ;
  localparam integer BAUD_I = BAUD;
  localparam integer MAXP_I = MAX_PAYLOAD;
  localparam integer SLEN_I = STATUS_LEN;
  localparam [7:0] NAX8 = NAX_I[7:0];
  localparam [15:0] DEPTH16 = DEPTH_I[15:0];
  localparam [31:0] CLK32 = CLK_I;
  localparam [31:0] BAUD32 = BAUD_I;
  localparam [31:0] BUILD32 = BUILD_ID;
  localparam [7:0] MAXP8 = MAXP_I[7:0];
  localparam [7:0] SLEN8 = SLEN_I[7:0];
  localparam integer TLEN_I = `FPGACNC_LENI_TRIGGER_REPORT_HEADER +
                              `FPGACNC_LENI_TRIGGER_REPORT_PER_AXIS * N_AXES;
  localparam [7:0] TLEN8 = TLEN_I[7:0];

  localparam [2:0] E_IDLE = 3'd0, E_SYNC = 3'd1, E_BODY = 3'd2, E_CRCH = 3'd3, E_CRCL = 3'd4;

  reg [2:0] st_reg;
  reg [SHW-1:0] sh_reg;
  reg [6:0] body_cnt_reg;  // body bytes (LEN, SEQ, TYPE, payload) still to send
  reg [7:0] dseq_reg;
  reg [7:0] aa_cnt_reg;
  reg ident_p_reg, status_p_reg, trig_p_reg, nak_p_reg, ack_p_reg, done_p_reg;
  reg [7:0] nak_seq_reg, nak_reason_reg;
  reg [7:0] tdata_reg;
  reg tvalid_reg;
  reg start_reg;

  wire [15:0] crc;
  wire take = tvalid_reg && m_axis_tready;

  // ---------------------------------------------------------------- frame images
  reg [32*N_AXES-1:0] pos_be, tpos_be;  // axis 0 first (most significant)
  integer a;
  always @(*)
    for (a = 0; a < N_AXES; a = a + 1) begin
      pos_be[32*(N_AXES-1-a)+:32]  = position[32*a+:32];
      tpos_be[32*(N_AXES-1-a)+:32] = trig_pos[32*a+:32];
    end

  /* verilator lint_off UNUSEDSIGNAL */
  wire [8*(3+STATUS_BASE)+127:0] img_status_full = {SLEN8, dseq_reg, `FPGACNC_T_STATUS, state,
                                                   faults, fifo_level, next_seq, segments_done,
                                                   pos_be, counters, limits, heat_status};
  /* verilator lint_on UNUSEDSIGNAL */
  wire [8*(3+STATUS_LEN)-1:0] img_status = img_status_full[8*(3+STATUS_BASE)+127-:8*(3+STATUS_LEN)];
  wire [8*21-1:0] img_ident = {`FPGACNC_LEN_IDENT, dseq_reg, `FPGACNC_T_IDENT, `FPGACNC_VERSION,
                               NAX8, DEPTH16, CLK32, BAUD32, BUILD32, next_seq, MAXP8};
  wire [8*8-1:0] img_nak = {`FPGACNC_LEN_NAK, dseq_reg, `FPGACNC_T_NAK, nak_seq_reg, nak_reason_reg,
                            next_seq, fifo_free};
  wire [8*3-1:0] img_ack_hdr = {`FPGACNC_LEN_ACK, dseq_reg,
                                ack_p_reg ? `FPGACNC_T_ACK : `FPGACNC_T_DONE};
  wire [8*10-1:0] img_ack = {img_ack_hdr, next_seq, fifo_free, segments_done};

  wire [8*(3+TLEN_I)-1:0] img_trig = {TLEN8, dseq_reg, `FPGACNC_T_TRIGGER_REPORT, trig_state,
                                      tpos_be};

  wire any_p = ident_p_reg || status_p_reg || trig_p_reg || nak_p_reg || ack_p_reg || done_p_reg;
  wire start = (st_reg == E_IDLE) && !tvalid_reg && (aa_cnt_reg == 8'd0) && any_p;

  reg [SHW-1:0] img;
  reg [6:0] img_bytes;
  always @(*) begin
    img = {SHW{1'b0}};
    if (ident_p_reg) begin
      img[SHW-1-:8*21] = img_ident;
      img_bytes = 7'd21;
    end else if (status_p_reg) begin
      img[SHW-1-:8*(3+STATUS_LEN)] = img_status;
      img_bytes = 7'd3 + SLEN8[6:0];
    end else if (trig_p_reg) begin
      img[SHW-1-:8*(3+TLEN_I)] = img_trig;
      img_bytes = 7'd3 + TLEN8[6:0];
    end else if (nak_p_reg) begin
      img[SHW-1-:8*8] = img_nak;
      img_bytes = 7'd8;
    end else begin
      img[SHW-1-:8*10] = img_ack;
      img_bytes = 7'd10;
    end
  end

  crc16_ccitt u_crc (
      .clk (clk),
      .rst (rst),
      .init(st_reg == E_SYNC),
      .en  (take && st_reg == E_BODY),
      .data(tdata_reg),
      .crc (crc)
  );

  always @(posedge clk) begin
    start_reg <= start;
    // Pending flags: sets win over the clear of a frame starting on the same edge.
    ident_p_reg  <= ident_req || (ident_p_reg && !(start && ident_p_reg));
    status_p_reg <= status_req || (status_p_reg && !(start && !ident_p_reg));
    trig_p_reg   <= trig_req || (trig_p_reg && !(start && !ident_p_reg && !status_p_reg));
    nak_p_reg    <= nak_req ||
                    (nak_p_reg && !(start && !ident_p_reg && !status_p_reg && !trig_p_reg));
    ack_p_reg    <= ack_req || (ack_p_reg && !(start && !ident_p_reg && !status_p_reg &&
                                               !trig_p_reg && !nak_p_reg));
    done_p_reg   <= done_evt || (done_p_reg && !(start && !ident_p_reg && !status_p_reg &&
                                                 !trig_p_reg && !nak_p_reg));
    if (nak_req) begin
      nak_seq_reg    <= nak_seq;
      nak_reason_reg <= nak_reason;
    end
    case ({v1_ack, st_reg == E_IDLE && take})
      2'b10:   aa_cnt_reg <= aa_cnt_reg + 8'd1;
      2'b01:   aa_cnt_reg <= aa_cnt_reg - 8'd1;
      default: aa_cnt_reg <= aa_cnt_reg;
    endcase

    case (st_reg)
      E_IDLE: begin
        if (take) begin
          tvalid_reg <= 1'b0;
        end else if (!tvalid_reg && aa_cnt_reg != 8'd0) begin
          tvalid_reg <= 1'b1;
          tdata_reg  <= `FPGACNC_V1_ACK;
        end else if (start) begin
          sh_reg       <= img;
          body_cnt_reg <= img_bytes;
          st_reg       <= E_SYNC;
          tvalid_reg   <= 1'b1;
          tdata_reg    <= `FPGACNC_SYNC;
        end
      end
      E_SYNC: begin
        if (take) begin
          st_reg    <= E_BODY;
          tdata_reg <= sh_reg[SHW-1-:8];
          sh_reg    <= {sh_reg[SHW-9:0], 8'h00};
        end
      end
      E_BODY: begin
        if (take) begin
          body_cnt_reg <= body_cnt_reg - 7'd1;
          if (body_cnt_reg == 7'd1) begin
            st_reg    <= E_CRCH;
            tvalid_reg <= 1'b0;  // the CRC of the last byte is ready on the next edge
          end else begin
            tdata_reg <= sh_reg[SHW-1-:8];
            sh_reg    <= {sh_reg[SHW-9:0], 8'h00};
          end
        end
      end
      E_CRCH: begin
        if (!tvalid_reg) begin
          tvalid_reg <= 1'b1;
          tdata_reg  <= crc[15:8];
        end else if (take) begin
          st_reg    <= E_CRCL;
          tdata_reg <= crc[7:0];
        end
      end
      default: begin  // E_CRCL
        if (take) begin
          st_reg     <= E_IDLE;
          tvalid_reg <= 1'b0;
          dseq_reg   <= dseq_reg + 8'd1;
        end
      end
    endcase

    if (rst) begin
      st_reg         <= E_IDLE;
      sh_reg         <= {SHW{1'b0}};
      body_cnt_reg   <= 7'd0;
      dseq_reg       <= 8'd0;
      aa_cnt_reg     <= 8'd0;
      ident_p_reg    <= 1'b0;
      status_p_reg   <= 1'b0;
      trig_p_reg     <= 1'b0;
      nak_p_reg      <= 1'b0;
      ack_p_reg      <= 1'b0;
      done_p_reg     <= 1'b0;
      nak_seq_reg    <= 8'd0;
      nak_reason_reg <= 8'd0;
      tdata_reg      <= 8'd0;
      tvalid_reg     <= 1'b0;
      start_reg      <= 1'b0;
    end
  end

  assign m_axis_tdata  = tdata_reg;
  assign m_axis_tvalid = tvalid_reg;
  assign frame_start   = start_reg;

endmodule

`default_nettype wire
