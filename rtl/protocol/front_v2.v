// front_v2: cnc_core's front end in the protocol-v2 builds (PROTO_V2 = 1): frame_decoder (v1
// packets and v2 frames) and the command FIFO whose entries go to segment_prep
// (docs/architecture.md "Code flow in the device", steps 2 and 3).
//
// Contract
//   s_axis_*     bytes from uart_rx; always ready (frame_decoder's s_axis_tready).
//   m_axis_*     command-FIFO entries for segment_prep, first-word fall-through (segment_fifo), in
//                segment_prep's layout of ENTRY_W = FPGACNC_ENTRY_W + 32 * N_AXES bits. The FIFO
//                stores only the fields of the kinds built (the ARC layout with ARCS, else the
//                LINE_PROFILE layout with PROFILES, else the base layout: docs/architecture.md
//                "Command-FIFO entry"); the bits above them read 0.
//   flush        empties the FIFO on this edge (an entry offered on it is dropped) and resyncs
//                frame_decoder's queued end positions (travel_guard) to position: cnc_core holds it
//                high on e-stop and on the hard-limit alarm.
//   resync       resyncs the queued end positions only (the clock after a SET_POSITION wrote the
//                position counters).
//   level, free  entries in the FIFO and free slots (the ACK credit), registers.
//   cfg_*, heat_*, fault_clear, hello, status_req, ack_req, nak*, next_seq, v2_mode, partial and
//                the status strobes, trig_wr, setpos_wr, trig_query, ctl_data, motion_quiet:
//                frame_decoder's (rtl/protocol/frame_decoder.v); RELEASE is not used.
// Build options (cnc_core passes its own): PROFILES, ARCS, OUTPUTS, HEATERS, TRIGGER 0 or 1 (a frame of a
// kind not built is answered NAK UNKNOWN_TYPE); FIFO_DEPTH a power of two, 2..32768. An illegal
// value instantiates a module named front_v2_illegal_<rule>, which does not exist.
`default_nettype none
`include "fpgacnc_spec.vh"

module front_v2 #(
    parameter N_AXES        = `FPGACNC_DEF_N_AXES,
    parameter WATCHDOG_CLKS = `FPGACNC_DEF_CLK_HZ / 10,  // inter-byte watchdog, clocks
    parameter FIFO_DEPTH    = `FPGACNC_DEF_FIFO_DEPTH,
    parameter PROFILES      = 1,
    parameter ARCS          = 1,
    parameter OUTPUTS       = 1,
    parameter HEATERS       = 1,
    parameter TRIGGER       = 0
) (
    input wire clk,
    input wire rst,

    input  wire [7:0] s_axis_tdata,
    input  wire       s_axis_tvalid,
    output wire       s_axis_tready,

    output wire [`FPGACNC_ENTRY_W+32*N_AXES-1:0] m_axis_tdata,
    output wire                                  m_axis_tvalid,
    input  wire                                  m_axis_tready,

    input  wire                flush,
    input  wire                resync,
    input  wire [32*N_AXES-1:0] position,
    output wire [        15:0] level,
    output wire [        15:0] free,

    output wire         cfg_wr,
    output wire [  7:0] cfg_axis,
    output wire [ 63:0] cfg_data,
    output wire         heat_wr,
    output wire [  7:0] heat_type,
    output wire [  7:0] heat_len,
    output wire [159:0] heat_data,
    output wire         fault_clear,
    output wire         hello,
    output wire         status_req,
    output wire         motion_set,
    output wire [ 71:0] motion_data,
    output wire         trig_wr,
    output wire         setpos_wr,
    output wire         trig_query,
    output wire [8*(2+4*N_AXES)-1:0] ctl_data,
    input  wire         motion_quiet,
    output wire         ack_req,
    output wire         nak,
    output wire [  7:0] nak_seq,
    output wire [  7:0] nak_reason,
    output wire [  7:0] next_seq,
    output wire         v2_mode,
    output wire         partial,
    output wire         frame_ok,
    output wire         crc_error,
    output wire         length_error,
    output wire         unknown_type,
    output wire         timeout,
    output wire         noise,
    output wire         v1_packet,
    output wire         v1_overrun
);

  localparam ENTRY_W = `FPGACNC_ENTRY_W + 32 * N_AXES;
  // the FIFO holds only the fields of the kinds built (segment_prep's entry layout)
  localparam integer FIFO_W = (ARCS != 0)     ? ENTRY_W :
                              (PROFILES != 0) ? `FPGACNC_ENTRY_PROF_W + 32 * N_AXES
                                              : `FPGACNC_ENTRY_BASE_W + 32 * N_AXES;

  generate
    if (PROFILES != 0 && PROFILES != 1) begin : g_bad_profiles
      front_v2_illegal_PROFILES_not_0_or_1 u_err ();
    end
    if (ARCS != 0 && ARCS != 1) begin : g_bad_arcs
      front_v2_illegal_ARCS_not_0_or_1 u_err ();
    end
    if (OUTPUTS != 0 && OUTPUTS != 1) begin : g_bad_outputs
      front_v2_illegal_OUTPUTS_not_0_or_1 u_err ();
    end
    if (HEATERS != 0 && HEATERS != 1) begin : g_bad_heaters
      front_v2_illegal_HEATERS_not_0_or_1 u_err ();
    end
    if (TRIGGER != 0 && TRIGGER != 1) begin : g_bad_trigger
      front_v2_illegal_TRIGGER_not_0_or_1 u_err ();
    end
    if (FIFO_DEPTH < 2 || FIFO_DEPTH > 32768 || (FIFO_DEPTH & (FIFO_DEPTH - 1)) != 0)
    begin : g_bad_fifo_depth
      front_v2_illegal_FIFO_DEPTH_not_power_of_2_in_2_to_32768 u_err ();
    end
  endgenerate

  wire [ENTRY_W-1:0] dec_tdata;
  wire dec_tvalid, fifo_s_tready;
  /* verilator lint_off UNUSEDSIGNAL */
  wire dec_release;  // not needed here
  /* verilator lint_on UNUSEDSIGNAL */

  frame_decoder #(
      .N_AXES       (N_AXES),
      .WATCHDOG_CLKS(WATCHDOG_CLKS),
      .MAX_PAYLOAD  (64),
      .PROFILES     (PROFILES),
      .ARCS         (ARCS),
      .OUTPUTS      (OUTPUTS),
      .HEATERS      (HEATERS),
      .TRIGGER      (TRIGGER)
  ) u_dec (
      .clk          (clk),
      .rst          (rst),
      .s_axis_tdata (s_axis_tdata),
      .s_axis_tvalid(s_axis_tvalid),
      .s_axis_tready(s_axis_tready),
      .m_axis_tdata (dec_tdata),
      .m_axis_tvalid(dec_tvalid),
      .m_axis_tready(fifo_s_tready),
      .cfg_wr       (cfg_wr),
      .cfg_axis     (cfg_axis),
      .cfg_data     (cfg_data),
      .heat_wr      (heat_wr),
      .heat_type    (heat_type),
      .heat_len     (heat_len),
      .heat_data    (heat_data),
      .fault_clear  (fault_clear),
      .release_req  (dec_release),
      .hello        (hello),
      .status_req   (status_req),
      .motion_set   (motion_set),
      .motion_data  (motion_data),
      .trig_wr      (trig_wr),
      .setpos_wr    (setpos_wr),
      .trig_query   (trig_query),
      .ctl_data     (ctl_data),
      .motion_quiet (motion_quiet),
      .ack_req      (ack_req),
      .nak          (nak),
      .nak_seq      (nak_seq),
      .nak_reason   (nak_reason),
      .travel_resync(flush || resync),
      .position     (position),
      .next_seq     (next_seq),
      .v2_mode      (v2_mode),
      .partial      (partial),
      .frame_ok     (frame_ok),
      .crc_error    (crc_error),
      .length_error (length_error),
      .unknown_type (unknown_type),
      .timeout      (timeout),
      .noise        (noise),
      .v1_packet    (v1_packet),
      .v1_overrun   (v1_overrun)
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
      .flush        (flush),
      .s_axis_tdata (dec_tdata[FIFO_W-1:0]),
      .s_axis_tvalid(dec_tvalid),
      .s_axis_tready(fifo_s_tready),
      .m_axis_tdata (fifo_out),
      .m_axis_tvalid(m_axis_tvalid),
      .m_axis_tready(m_axis_tready),
      .level        (level),
      .free         (free)
  );
  generate
    if (FIFO_W < ENTRY_W) begin : g_pad
      assign m_axis_tdata = {{(ENTRY_W - FIFO_W) {1'b0}}, fifo_out};
    end else begin : g_nopad
      assign m_axis_tdata = fifo_out;
    end
  endgenerate

endmodule

`default_nettype wire
