// status_counters: cnc_core's status registers: the last move's fields, the event counters of
// STATUS and of the status pins, the completed-entry count, and the faults byte with its STEP
// timing and arc fault latches (docs/protocol.md "STATUS").
//
// Contract
//   seg_accept       segment_executor takes a segment (segment_prep's m_axis handshake): last_code,
//                    last_feed, last_period take seg_code, seg_feed, seg_period.
//   counters         16 bits each, +1 on every clock its strobe is high, wrapping:
//                    packet_count   v1_packet or frame_ok
//                    frame_errors   rx_frame_error (uart_rx)
//                    timeouts       timeout (the decoder's watchdog)
//                    overruns       v1_overrun or rx_overrun
//                    violations     violation (segment_executor: STEP timing)
//                    frames_ok, crc_errors, length_errors, unknown_types, noise_bytes, naks
//                                   frame_ok, crc_error, length_error, unknown_type, noise, nak
//                    clamped        prep_clamped (a v2 segment whose T was raised)
//   segments_done    32 bits, + v2_seg_done + v2_init_done + (out_done ? out_done_n : 0) each clock.
//   faults           {heat_faults1 != 0, heat_faults0 != 0, heat_wd_fault, estop_latched, 0,
//                    limit_trip, arc fault, step fault}: the step fault is set by violation, the
//                    arc fault by arc_err; fault_clear clears both unless their strobe is high in
//                    the same clock.
//   rst              synchronous: every register 0.
`default_nettype none

module status_counters (
    input wire clk,
    input wire rst,

    input wire        seg_accept,
    input wire [ 1:0] seg_code,
    input wire [15:0] seg_feed,
    input wire [31:0] seg_period,

    input wire v1_packet,
    input wire frame_ok,
    input wire rx_frame_error,
    input wire timeout,
    input wire v1_overrun,
    input wire rx_overrun,
    input wire violation,
    input wire crc_error,
    input wire length_error,
    input wire unknown_type,
    input wire noise,
    input wire prep_clamped,
    input wire nak,

    input wire        v2_seg_done,
    input wire        v2_init_done,
    input wire        out_done,
    input wire [15:0] out_done_n,

    input wire       fault_clear,
    input wire       arc_err,
    input wire [7:0] heat_faults0,
    input wire [7:0] heat_faults1,
    input wire       heat_wd_fault,
    input wire       estop_latched,
    input wire       limit_trip,

    output wire [ 1:0] last_code,
    output wire [15:0] last_feed,
    output wire [31:0] last_period,
    output wire [15:0] packet_count,
    output wire [15:0] frame_errors,
    output wire [15:0] timeouts,
    output wire [15:0] overruns,
    output wire [15:0] violations,
    output wire [15:0] frames_ok,
    output wire [15:0] crc_errors,
    output wire [15:0] length_errors,
    output wire [15:0] unknown_types,
    output wire [15:0] noise_bytes,
    output wire [15:0] clamped,
    output wire [15:0] naks,
    output wire [31:0] segments_done,
    output wire [ 7:0] faults
);

  reg [1:0] last_code_reg;
  reg [15:0] last_feed_reg;
  reg [31:0] last_period_reg;
  reg [15:0] packet_count_reg, frame_errors_reg, timeouts_reg, overruns_reg, violations_reg;
  reg [15:0] frames_ok_reg, crc_errors_reg, length_errors_reg, unknown_types_reg;
  reg [15:0] noise_bytes_reg, clamped_reg, naks_reg;
  reg [31:0] segments_done_reg;
  reg fault_step_reg;
  reg fault_arc_reg;  // an ARC ended inconsistently (faults bit 1)

  always @(posedge clk) begin
    if (seg_accept) begin
      last_code_reg   <= seg_code;
      last_feed_reg   <= seg_feed;
      last_period_reg <= seg_period;
    end
    if (v1_packet || frame_ok) packet_count_reg <= packet_count_reg + 16'd1;
    if (rx_frame_error) frame_errors_reg <= frame_errors_reg + 16'd1;
    if (timeout) timeouts_reg <= timeouts_reg + 16'd1;
    if (v1_overrun || rx_overrun) overruns_reg <= overruns_reg + 16'd1;
    if (violation) violations_reg <= violations_reg + 16'd1;
    if (frame_ok) frames_ok_reg <= frames_ok_reg + 16'd1;
    if (crc_error) crc_errors_reg <= crc_errors_reg + 16'd1;
    if (length_error) length_errors_reg <= length_errors_reg + 16'd1;
    if (unknown_type) unknown_types_reg <= unknown_types_reg + 16'd1;
    if (noise) noise_bytes_reg <= noise_bytes_reg + 16'd1;
    if (prep_clamped) clamped_reg <= clamped_reg + 16'd1;
    if (nak) naks_reg <= naks_reg + 16'd1;
    segments_done_reg <= segments_done_reg + {31'd0, v2_seg_done} + {31'd0, v2_init_done} +
                         (out_done ? {16'd0, out_done_n} : 32'd0);
    if (fault_clear) fault_step_reg <= 1'b0;
    if (violation) fault_step_reg <= 1'b1;
    if (fault_clear) fault_arc_reg <= 1'b0;
    if (arc_err) fault_arc_reg <= 1'b1;
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

  assign last_code     = last_code_reg;
  assign last_feed     = last_feed_reg;
  assign last_period   = last_period_reg;
  assign packet_count  = packet_count_reg;
  assign frame_errors  = frame_errors_reg;
  assign timeouts      = timeouts_reg;
  assign overruns      = overruns_reg;
  assign violations    = violations_reg;
  assign frames_ok     = frames_ok_reg;
  assign crc_errors    = crc_errors_reg;
  assign length_errors = length_errors_reg;
  assign unknown_types = unknown_types_reg;
  assign noise_bytes   = noise_bytes_reg;
  assign clamped       = clamped_reg;
  assign naks          = naks_reg;
  assign segments_done = segments_done_reg;
  assign faults = {heat_faults1 != 8'd0, heat_faults0 != 8'd0, heat_wd_fault, estop_latched, 1'b0,
                   limit_trip, fault_arc_reg, fault_step_reg};

endmodule

`default_nettype wire
