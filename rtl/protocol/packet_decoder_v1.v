// packet_decoder_v1: byte-exact decoder of the original controller's protocol v1 (packets:
// docs/protocol.md "v1"), the decoder of cnc_core's PROTO_V2 = 0 builds.
//
// Contract
// Input: a byte stream (s_axis_*) from uart_rx; s_axis_tready is always high.
// Output: one command per complete packet on m_axis_* (held until accepted):
//   m_axis_tuser = 1 for init, 0 for motion
//   m_axis_tdata = {code[1:0], a[31:0], b[31:0], feed[15:0]}
//                  init:   a = NUMERATOR_X, b = NUMERATOR_Y, code = 3, feed = 0
//                  motion: a = steps_x,     b = steps_y
// Latency: the command is valid on the clock after the packet's last byte is accepted.
// Watchdog: when a packet has started and no byte arrives for WATCHDOG_CLKS clocks, the partial
// packet is dropped (timeout strobe) and the next byte starts a new packet.
// Overrun: a packet completing while the previous command is still not accepted is dropped
// (overrun strobe; a v1 host waits for each move's 0xAA, so only a misbehaving host meets it).
`default_nettype none

module packet_decoder_v1 #(
    parameter WATCHDOG_CLKS = 5_000_000  // 100 ms at 50 MHz
) (
    input wire clk,
    input wire rst,

    input  wire [7:0] s_axis_tdata,
    input  wire       s_axis_tvalid,
    output wire       s_axis_tready,

    output wire [81:0] m_axis_tdata,
    output wire        m_axis_tuser,
    output wire        m_axis_tvalid,
    input  wire        m_axis_tready,

    output wire timeout,      // 1-clock strobe: partial packet dropped by the watchdog
    output wire overrun,      // 1-clock strobe: complete packet dropped, output still full
    output wire packet_done,  // 1-clock strobe: a complete packet was decoded and queued
    output wire partial       // a packet has started and is not complete yet
);

  localparam WD_W = $clog2(WATCHDOG_CLKS + 1);
  localparam integer WD_LAST_I = WATCHDOG_CLKS - 1;
  localparam [WD_W-1:0] WD_LAST = WD_LAST_I[WD_W-1:0];

  reg  [    3:0] count_reg;  // bytes of the current packet received so far
  reg            is_init_reg;
  reg  [    1:0] code_reg;
  reg  [   71:0] shift_reg;  // bytes 1..9 so far (byte 10 is the one arriving), MSB first
  reg  [WD_W-1:0] idle_reg;  // clocks since the last byte of a started packet

  reg  [   81:0] out_data_reg;
  reg            out_user_reg;
  reg            out_valid_reg;
  reg            timeout_reg;
  reg            overrun_reg;
  reg            done_reg;

  wire           take = s_axis_tvalid;
  wire           first = (count_reg == 4'd0);
  wire           start_init = first && (s_axis_tdata == 8'hFF);
  wire [    3:0] length = (first ? start_init : is_init_reg) ? 4'd9 : 4'd11;
  wire           last = take && (count_reg == length - 4'd1);
  wire [   79:0] shifted = {shift_reg[71:0], s_axis_tdata};

  always @(posedge clk) begin
    timeout_reg <= 1'b0;
    overrun_reg <= 1'b0;
    done_reg    <= 1'b0;
    if (out_valid_reg && m_axis_tready) out_valid_reg <= 1'b0;

    if (take) begin
      idle_reg <= {WD_W{1'b0}};
      if (first) begin
        is_init_reg <= start_init;
        code_reg    <= s_axis_tdata[1:0];
      end
      shift_reg <= shifted[71:0];
      if (last) begin
        count_reg <= 4'd0;
        if (out_valid_reg && !m_axis_tready) begin
          overrun_reg <= 1'b1;
        end else begin
          out_valid_reg <= 1'b1;
          done_reg      <= 1'b1;
          out_user_reg  <= is_init_reg;
          // init: 8 payload bytes are in shifted[63:0]; motion: 10 bytes in shifted[79:0]
          if (is_init_reg) out_data_reg <= {2'b11, shifted[63:32], shifted[31:0], 16'd0};
          else out_data_reg <= {code_reg, shifted[79:48], shifted[47:16], shifted[15:0]};
        end
      end else begin
        count_reg <= count_reg + 4'd1;
      end
    end else if (!first) begin
      if (idle_reg == WD_LAST) begin
        count_reg   <= 4'd0;
        idle_reg    <= {WD_W{1'b0}};
        timeout_reg <= 1'b1;
      end else begin
        idle_reg <= idle_reg + {{(WD_W - 1) {1'b0}}, 1'b1};
      end
    end

    if (rst) begin
      count_reg     <= 4'd0;
      is_init_reg   <= 1'b0;
      code_reg      <= 2'd0;
      shift_reg     <= 72'd0;
      idle_reg      <= {WD_W{1'b0}};
      out_data_reg  <= 82'd0;
      out_user_reg  <= 1'b0;
      out_valid_reg <= 1'b0;
      timeout_reg   <= 1'b0;
      overrun_reg   <= 1'b0;
      done_reg      <= 1'b0;
    end
  end

  assign s_axis_tready = 1'b1;
  assign m_axis_tdata  = out_data_reg;
  assign m_axis_tuser  = out_user_reg;
  assign m_axis_tvalid = out_valid_reg;
  assign timeout       = timeout_reg;
  assign overrun       = overrun_reg;
  assign packet_done   = done_reg;
  assign partial       = (count_reg != 4'd0);

`ifdef FORMAL
  // Formal properties (scripts/formal.sh, k-induction with a small WATCHDOG_CLKS override).
  // An independent monitor counts the bytes since the last packet boundary the decoder reported
  // (packet_done, overrun or timeout) and the idle clocks since the last byte.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  localparam integer F_W = WD_W + 1;
  localparam [F_W-1:0] F_WD = WATCHDOG_CLKS;

  reg  [    3:0] f_n;     // bytes of the current packet, including those of a packet just ended
  reg            f_init;  // the current packet's first byte was 0xFF
  reg  [F_W-1:0] f_idle;  // clocks without a byte since the last byte, saturating at WATCHDOG+1
  wire           f_boundary = done_reg || overrun_reg || timeout_reg;
  wire [    3:0] f_n_eff = f_boundary ? 4'd0 : f_n;  // bytes of the packet still open
  wire [    3:0] f_len = f_init ? 4'd9 : 4'd11;

  always @(posedge clk) begin
    if (take) begin
      f_n    <= f_n_eff + 4'd1;
      f_idle <= {F_W{1'b0}};
      if (f_n_eff == 4'd0) f_init <= (s_axis_tdata == 8'hFF);
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
    if (f_past_valid) begin
      // A command (packet_done, or overrun for a dropped complete packet) only after exactly the
      // packet's length in bytes: 9 for init (first byte 0xFF), 11 for motion.
      if (done_reg || overrun_reg) assert (f_n == f_len);
      assert (!(done_reg && overrun_reg) && !(timeout_reg && (done_reg || overrun_reg)));
      // Never more bytes than the packet's length.
      assert (f_n <= f_len);
      // The watchdog drops only a partial packet, and only after exactly WATCHDOG_CLKS clocks
      // without a byte ...
      if (timeout_reg) assert (f_n != 4'd0 && f_n < f_len && f_idle == F_WD);
      // ... and always then.
      if (f_n != 4'd0 && !done_reg && !overrun_reg && f_idle == F_WD) assert (timeout_reg);
      if (f_n_eff != 4'd0) assert (f_idle < F_WD);
      // Induction invariants: the decoder's counters match the monitor.
      assert (count_reg == f_n_eff);
      if (count_reg != 4'd0) assert (is_init_reg == f_init && idle_reg == f_idle[WD_W-1:0]);
      else assert (idle_reg == {WD_W{1'b0}});
      assert (f_idle <= F_WD + 1);
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst)) begin
      // m_axis_tvalid rises only with packet_done, and a held command is never replaced.
      if (!$past(out_valid_reg) && out_valid_reg) assert (done_reg);
      if ($past(out_valid_reg) && !$past(m_axis_tready)) assert (out_valid_reg);
    end
`endif

endmodule

`default_nettype wire
