// answer_source: the byte stream cnc_core sends through uart_tx (docs/architecture.md "Code flow in
// the device", step 6): response_encoder's device frames in the protocol-v2 builds, a 0xAA per
// completed v1 move in the protocol-v1-only builds.
//
// Contract
//   m_axis_*     bytes for uart_tx, held until taken.
//   PROTO_V2 = 1 response_encoder (rtl/protocol/response_encoder.v) with 64-byte payloads and the 16 heater
//                bytes of STATUS: the request strobes (ident_req .. v1_ack) and the live state go to
//                it; this module forms STATUS's state byte {probe, stopped, hold, limit_untrusted,
//                estop_active, faults != 0, v2_mode, busy} and its limit bytes {0, 0, 0,
//                limit_trip_max, limit_trip_axis} and the switch states u16 (bit a = lim_min of axis
//                a, bit 8 + a = lim_max; axes 0..7 only); counters are STATUS's nine u16 in order
//                (frames_ok, crc_errors, length_errors, unknown_types, timeouts, frame_errors,
//                overruns, noise_bytes, clamped); trig_req, trig_state, trig_pos: TRIGGER_REPORT.
//   PROTO_V2 = 0 an 8-bit count of the 0xAA answers owed: v1_ack (a completed v1 move) adds one, each
//                0xAA taken subtracts one; 0xAA is offered while the count is not 0. The v2
//                requests and state are not read.
//   rst          synchronous: nothing pending.
// PROTO_V2 0 or 1, N_AXES 1..15; an illegal value instantiates a module named
// answer_source_illegal_<rule>, which does not exist.
`default_nettype none
`include "fpgacnc_spec.vh"

module answer_source #(
    parameter PROTO_V2   = 1,
    parameter N_AXES     = `FPGACNC_DEF_N_AXES,
    parameter FIFO_DEPTH = `FPGACNC_DEF_FIFO_DEPTH,
    parameter CLK_HZ     = `FPGACNC_DEF_CLK_HZ,
    parameter BAUD       = `FPGACNC_DEF_BAUD,
    parameter BUILD_ID   = `FPGACNC_BUILD_ID
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

    input wire [          7:0] next_seq,
    input wire [         15:0] fifo_free,
    input wire [         15:0] fifo_level,
    input wire [         31:0] segments_done,
    input wire                 busy,
    input wire                 v2_mode,
    input wire                 estop_active,
    input wire                 limit_untrusted,
    input wire                 hold,            // feed hold in effect (feed_rate)
    input wire                 stopped,         // motion rate 0 (feed_rate)
    input wire                 probe,           // the filtered probe input (trigger builds)
    input wire [          7:0] faults,
    input wire [32*N_AXES-1:0] position,
    input wire [     16*9-1:0] counters,
    input wire                 limit_trip_max,
    input wire [          3:0] limit_trip_axis,
    input wire [   N_AXES-1:0] lim_min,
    input wire [   N_AXES-1:0] lim_max,
    input wire [        127:0] heat_status,
    input wire [         31:0] trig_state,
    input wire [32*N_AXES-1:0] trig_pos,

    output wire [7:0] m_axis_tdata,
    output wire       m_axis_tvalid,
    input  wire       m_axis_tready
);

  generate
    if (PROTO_V2 != 0 && PROTO_V2 != 1) begin : g_bad_proto_v2
      answer_source_illegal_PROTO_V2_not_0_or_1 u_err ();
    end
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      answer_source_illegal_N_AXES_not_1_to_15 u_err ();
    end
  endgenerate

  generate
    if (PROTO_V2 != 0) begin : g_enc
      /* verilator lint_off UNUSEDSIGNAL */
      wire enc_frame_start;  // not needed here
      /* verilator lint_on UNUSEDSIGNAL */
      wire [7:0] state_w = {probe, stopped, hold, limit_untrusted, estop_active, faults != 8'd0,
                            v2_mode, busy};
      /* verilator lint_off UNUSEDSIGNAL */
      wire [15:0] lim_min16 = {{(16 - N_AXES) {1'b0}}, lim_min};  // axes 8..14 not reported
      wire [15:0] lim_max16 = {{(16 - N_AXES) {1'b0}}, lim_max};
      /* verilator lint_on UNUSEDSIGNAL */
      wire [23:0] limits_w = {3'd0, limit_trip_max, limit_trip_axis, lim_max16[7:0], lim_min16[7:0]};

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
          .ident_req    (ident_req),
          .status_req   (status_req),
          .trig_req     (trig_req),
          .nak_req      (nak_req),
          .nak_seq      (nak_seq),
          .nak_reason   (nak_reason),
          .ack_req      (ack_req),
          .done_evt     (done_evt),
          .v1_ack       (v1_ack),
          .next_seq     (next_seq),
          .fifo_free    (fifo_free),
          .fifo_level   (fifo_level),
          .segments_done(segments_done),
          .state        (state_w),
          .faults       (faults),
          .position     (position),
          .counters     (counters),
          .limits       (limits_w),
          .heat_status  (heat_status),
          .trig_state   (trig_state),
          .trig_pos     (trig_pos),
          .m_axis_tdata (m_axis_tdata),
          .m_axis_tvalid(m_axis_tvalid),
          .m_axis_tready(m_axis_tready),
          .frame_start  (enc_frame_start)
      );
    end else begin : g_aa
      reg [7:0] aa_cnt_reg;
      wire aa_take = m_axis_tvalid && m_axis_tready;
      always @(posedge clk) begin
        case ({v1_ack, aa_take})
          2'b10:   aa_cnt_reg <= aa_cnt_reg + 8'd1;
          2'b01:   aa_cnt_reg <= aa_cnt_reg - 8'd1;
          default: aa_cnt_reg <= aa_cnt_reg;
        endcase
        if (rst) aa_cnt_reg <= 8'd0;
      end
      assign m_axis_tdata  = `FPGACNC_V1_ACK;
      assign m_axis_tvalid = (aa_cnt_reg != 8'd0);
      wire unused_v2 = &{1'b0, ident_req, status_req, nak_req, nak_seq, nak_reason, ack_req,
                         done_evt, next_seq, fifo_free, fifo_level, segments_done, busy, v2_mode,
                         estop_active, limit_untrusted, hold, stopped, faults, position, counters,
                         limit_trip_max, limit_trip_axis, lim_min, lim_max, heat_status,
                         trig_req, probe, trig_state, trig_pos};
    end
  endgenerate

endmodule

`default_nettype wire
