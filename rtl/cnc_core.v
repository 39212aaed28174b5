// cnc_core: the board-independent controller, protocol v1.
//
//   rx -> uart_rx -> packet_decoder_v1 -> segment_prep -> segment_executor -> STEP/DIR/laser
//   tx <- uart_tx <- ACK 0xAA per completed move
//
// Behaviour (protocol-v1.md): init packets set NUMERATOR_X/Y once the machine is idle; a motion
// packet runs as one constant-rate segment; when it completes (the executor's last tick, or at
// once for a move with no steps) one 0xAA byte is queued to uart_tx.
// Runtime configuration port (cfg_wr/cfg_addr/cfg_wdata, one write per clock): per-axis step
// timing in clocks, address = axis * 4 + field, field 0 STEP high, 1 STEP low, 2 DIR setup,
// 3 DIR hold (16 bits each; defaults STEP_HIGH/STEP_LOW/DIR_SETUP/DIR_HOLD). Writes land in a
// shadow set that becomes active only while nothing is prepared, queued or running, so a setting
// never changes in the middle of a move.
// rst is synchronous, active high; the board top synchronizes its reset button.
`default_nettype none

module cnc_core #(
    parameter CLK_HZ            = 50_000_000,
    parameter BAUD              = 115_200,
    parameter N_AXES            = 4,
    parameter WATCHDOG_CLKS     = CLK_HZ / 10,         // 100 ms packet watchdog
    parameter FEED0_PERIOD      = 62_500,              // dominant period when feed = 0
    parameter DEFAULT_NUMERATOR = CLK_HZ / 160 * 60,   // CLK_HZ * 60 / 160 steps/mm
    parameter STEP_HIGH         = 100,
    parameter STEP_LOW          = 100,
    parameter DIR_SETUP         = 200,
    parameter DIR_HOLD          = 200
) (
    input wire clk,
    input wire rst,

    input  wire rx,
    output wire tx,

    output wire [N_AXES-1:0] step,
    output wire [N_AXES-1:0] dir,
    output wire              laser,

    input wire        cfg_wr,
    input wire [ 7:0] cfg_addr,
    input wire [15:0] cfg_wdata,

    output wire                 busy,        // a move is prepared, waiting or running
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
    output wire [        31:0] numerator_y
);

  // ---------------------------------------------------------------- UART in
  wire [7:0] rx_tdata;
  wire rx_tvalid, rx_tready, rx_frame_error, rx_overrun;
  /* verilator lint_off UNUSEDSIGNAL */
  wire rx_busy, tx_busy, init_applied;  // not needed by the v1 core
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

  // ---------------------------------------------------------------- decoder
  wire [81:0] cmd_tdata;
  wire cmd_tuser, cmd_tvalid, cmd_tready;
  wire dec_timeout, dec_overrun, dec_done;

  packet_decoder_v1 #(
      .WATCHDOG_CLKS(WATCHDOG_CLKS)
  ) u_dec (
      .clk          (clk),
      .rst          (rst),
      .s_axis_tdata (rx_tdata),
      .s_axis_tvalid(rx_tvalid),
      .s_axis_tready(rx_tready),
      .m_axis_tdata (cmd_tdata),
      .m_axis_tuser (cmd_tuser),
      .m_axis_tvalid(cmd_tvalid),
      .m_axis_tready(cmd_tready),
      .timeout      (dec_timeout),
      .overrun      (dec_overrun),
      .packet_done  (dec_done)
  );

  // ---------------------------------------------------------------- configuration
  reg [16*N_AXES-1:0] shadow_high_reg, shadow_low_reg, shadow_setup_reg, shadow_hold_reg;
  reg [16*N_AXES-1:0] cfg_high_reg, cfg_low_reg, cfg_setup_reg, cfg_hold_reg;
  reg [31:0] min_period_reg;

  wire exec_idle;
  wire prep_busy;
  wire quiet = exec_idle && !prep_busy;

  // min_period = max over axes of (STEP high + STEP low), each at least 1, so at least 2: the fastest dominant period
  // the pulse generators can follow. Computed by a scanner, one axis per clock (no comparator
  // chain across axes): a change of the active settings reaches min_period_reg within
  // 2 * N_AXES + 2 clocks, long before segment_prep uses it (34 clocks after it accepts a move,
  // and settings change only while segment_prep is idle). Requires N_AXES <= 15.
  localparam AXW = (N_AXES > 1) ? $clog2(N_AXES) : 1;
  localparam integer AX_LAST_I = N_AXES - 1;
  localparam [AXW-1:0] AX_LAST = AX_LAST_I[AXW-1:0];
  reg [AXW-1:0] pm_idx_reg, pm_idx_d_reg;
  reg [16:0] pm_sum_reg, pm_run_reg;
  // step_pulse treats a setting of 0 as 1 clock: count it so here too.
  wire [15:0] pm_high_raw = cfg_high_reg[16*pm_idx_reg+:16];
  wire [15:0] pm_low_raw = cfg_low_reg[16*pm_idx_reg+:16];
  wire [15:0] pm_high = (pm_high_raw == 16'd0) ? 16'd1 : pm_high_raw;
  wire [15:0] pm_low = (pm_low_raw == 16'd0) ? 16'd1 : pm_low_raw;
  wire [16:0] pm_cand = (pm_idx_d_reg == {AXW{1'b0}} || pm_sum_reg > pm_run_reg) ? pm_sum_reg
                                                                                 : pm_run_reg;

  always @(posedge clk) begin
    if (cfg_wr && cfg_addr[7:2] < N_AXES) begin
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

  // ---------------------------------------------------------------- preparation
  // Stopgap until the v2 decoder and command FIFO: the v1 decoder's command as a FIFO entry
  // { v2, kind, code, power, t, steps } (kind 0 motion, 1 init; v1: t = feed, power 0xFF).
  localparam ENTRY_W = 45 + 32 * N_AXES;
  wire [ENTRY_W-1:0] cmd_entry;
  generate
    if (N_AXES > 2) begin : g_entry_wide
      assign cmd_entry = {1'b0, cmd_tuser ? 2'd1 : 2'd0, cmd_tdata[81:80], 8'hFF, 16'd0,
                          cmd_tdata[15:0], {(32 * (N_AXES - 2)) {1'b0}}, cmd_tdata[47:16],
                          cmd_tdata[79:48]};
    end else begin : g_entry_narrow
      assign cmd_entry = {1'b0, cmd_tuser ? 2'd1 : 2'd0, cmd_tdata[81:80], 8'hFF, 16'd0,
                          cmd_tdata[15:0], cmd_tdata[47:16], cmd_tdata[79:48]};
    end
  endgenerate

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
  /* verilator lint_off UNUSEDSIGNAL */
  wire init_v2, prep_clamped, seg_done_v2;  // v2 status, not used by the v1 core
  /* verilator lint_on UNUSEDSIGNAL */

  segment_prep #(
      .N_AXES           (N_AXES),
      .FEED0_PERIOD     (FEED0_PERIOD),
      .DEFAULT_NUMERATOR(DEFAULT_NUMERATOR)
  ) u_prep (
      .clk            (clk),
      .rst            (rst),
      .s_axis_tdata   (cmd_entry),
      .s_axis_tvalid  (cmd_tvalid),
      .s_axis_tready  (cmd_tready),
      .exec_idle      (exec_idle),
      .min_period     (min_period_reg),
      .cfg_dir_setup  (cfg_setup_reg),
      .cfg_dir_hold   (cfg_hold_reg),
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
      .m_axis_tvalid  (seg_tvalid),
      .m_axis_tready  (seg_tready),
      .numerator_x    (numerator_x),
      .numerator_y    (numerator_y),
      .init_applied   (init_applied),
      .init_v2        (init_v2),
      .clamped        (prep_clamped),
      .busy           (prep_busy)
  );

  // ---------------------------------------------------------------- execution
  wire exec_busy, exec_violation;

  segment_executor #(
      .N_AXES(N_AXES)
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
      .s_axis_tvalid  (seg_tvalid),
      .s_axis_tready  (seg_tready),
      .cfg_step_high  (cfg_high_reg),
      .cfg_step_low   (cfg_low_reg),
      .cfg_dir_setup  (cfg_setup_reg),
      .cfg_dir_hold   (cfg_hold_reg),
      .step           (step),
      .dir            (dir),
      .laser          (laser),
      .busy           (exec_busy),
      .idle           (exec_idle),
      .running        (running),
      .seg_start      (seg_start),
      .seg_done       (seg_done),
      .seg_done_v2    (seg_done_v2),
      .position       (position),
      .violation      (exec_violation)
  );

  // ---------------------------------------------------------------- ACK and status
  reg [7:0] ack_pending_reg;
  reg [1:0] last_code_reg;
  reg [15:0] last_feed_reg;
  reg [31:0] last_period_reg;
  reg [15:0] packet_count_reg, frame_errors_reg, timeouts_reg, overruns_reg, violations_reg;
  wire tx_tready;
  wire ack_send = (ack_pending_reg != 8'd0) && tx_tready;

  always @(posedge clk) begin
    case ({seg_done, ack_send})
      2'b10:   ack_pending_reg <= ack_pending_reg + 8'd1;
      2'b01:   ack_pending_reg <= ack_pending_reg - 8'd1;
      default: ack_pending_reg <= ack_pending_reg;
    endcase
    if (seg_tvalid && seg_tready) begin
      last_code_reg <= seg_code;
      last_feed_reg <= seg_feed;
      last_period_reg <= seg_period;
    end
    if (dec_done) packet_count_reg <= packet_count_reg + 16'd1;
    if (rx_frame_error) frame_errors_reg <= frame_errors_reg + 16'd1;
    if (dec_timeout) timeouts_reg <= timeouts_reg + 16'd1;
    if (dec_overrun || rx_overrun) overruns_reg <= overruns_reg + 16'd1;
    if (exec_violation) violations_reg <= violations_reg + 16'd1;
    if (rst) begin
      ack_pending_reg  <= 8'd0;
      last_code_reg    <= 2'd0;
      last_feed_reg    <= 16'd0;
      last_period_reg  <= 32'd0;
      packet_count_reg <= 16'd0;
      frame_errors_reg <= 16'd0;
      timeouts_reg     <= 16'd0;
      overruns_reg     <= 16'd0;
      violations_reg   <= 16'd0;
    end
  end

  uart_tx #(
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD)
  ) u_tx (
      .clk          (clk),
      .rst          (rst),
      .s_axis_tdata (8'hAA),
      .s_axis_tvalid(ack_pending_reg != 8'd0),
      .s_axis_tready(tx_tready),
      .txd          (tx),
      .busy         (tx_busy)
  );

  assign busy         = exec_busy || prep_busy || cmd_tvalid;
  assign last_code    = last_code_reg;
  assign last_feed    = last_feed_reg;
  assign last_period  = last_period_reg;
  assign packet_count = packet_count_reg;
  assign frame_errors = frame_errors_reg;
  assign timeouts     = timeouts_reg;
  assign overruns     = overruns_reg;
  assign violations   = violations_reg;

endmodule

`default_nettype wire
