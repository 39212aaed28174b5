// front_v1: cnc_core's front end in the protocol-v1-only builds (PROTO_V2 = 0): the original
// controller's packet_decoder_v1, whose output register is the only queue, with its commands
// shaped into segment_prep's entry (docs/architecture.md "Code flow in the device", step 2).
//
// Contract
//   s_axis_*     bytes from uart_rx; always ready (packet_decoder_v1's s_axis_tready).
//   m_axis_*     one entry per complete packet, held until taken, in segment_prep's layout of
//                ENTRY_W = FPGACNC_ENTRY_W + 32 * N_AXES bits, as frame_decoder writes a v1 packet:
//                motion {v2 0, kind MOTION, code, power 0xFF, T = feed, steps X, Y, other axes 0};
//                init {v2 0, kind NUMERATORS, NUMERATOR_X, NUMERATOR_Y}; every other bit 0.
//   level, free  the queue of one entry: level = m_axis_tvalid, free = !m_axis_tvalid.
//   timeout, overrun, packet_done, partial   packet_decoder_v1's (rtl/protocol/packet_decoder_v1.v).
// N_AXES at least 2 (v1 packets carry X and Y); a smaller value instantiates a module named
// front_v1_illegal_N_AXES_below_2, which does not exist.
`default_nettype none
`include "fpgacnc_spec.vh"

module front_v1 #(
    parameter N_AXES        = 2,
    parameter WATCHDOG_CLKS = `FPGACNC_DEF_CLK_HZ / 10  // inter-byte watchdog, clocks
) (
    input wire clk,
    input wire rst,

    input  wire [7:0] s_axis_tdata,
    input  wire       s_axis_tvalid,
    output wire       s_axis_tready,

    output wire [`FPGACNC_ENTRY_W+32*N_AXES-1:0] m_axis_tdata,
    output wire                                  m_axis_tvalid,
    input  wire                                  m_axis_tready,

    output wire [15:0] level,
    output wire [15:0] free,

    output wire timeout,
    output wire overrun,
    output wire packet_done,
    output wire partial
);

  localparam ENTRY_W = `FPGACNC_ENTRY_W + 32 * N_AXES;

  generate
    if (N_AXES < 2) begin : g_bad_n_axes
      front_v1_illegal_N_AXES_below_2 u_err ();
    end
  endgenerate

  wire [81:0] v1_tdata;
  wire v1_init;
  packet_decoder_v1 #(
      .WATCHDOG_CLKS(WATCHDOG_CLKS)
  ) u_dec (
      .clk          (clk),
      .rst          (rst),
      .s_axis_tdata (s_axis_tdata),
      .s_axis_tvalid(s_axis_tvalid),
      .s_axis_tready(s_axis_tready),
      .m_axis_tdata (v1_tdata),
      .m_axis_tuser (v1_init),
      .m_axis_tvalid(m_axis_tvalid),
      .m_axis_tready(m_axis_tready),
      .timeout      (timeout),
      .overrun      (overrun),
      .packet_done  (packet_done),
      .partial      (partial)
  );

  wire [32*N_AXES-1:0] v1_two = {{32 * (N_AXES - 2) {1'b0}}, v1_tdata[47:16], v1_tdata[79:48]};
  assign m_axis_tdata = {{(ENTRY_W - `FPGACNC_ENTRY_BASE_W - 32 * N_AXES) {1'b0}}, 1'b0,
                         v1_init ? `FPGACNC_K_NUMERATORS : `FPGACNC_K_MOTION,
                         v1_init ? 2'd0 : v1_tdata[81:80],
                         v1_init ? 8'd0 : 8'hFF, v1_init ? 16'd0 : 16'd0,
                         v1_init ? 16'd0 : v1_tdata[15:0], v1_two};
  assign level = {15'd0, m_axis_tvalid};
  assign free  = {15'd0, !m_axis_tvalid};

endmodule

`default_nettype wire
