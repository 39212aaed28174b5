// segment_prep: turns decoded v1 commands into segments the executor can run without arithmetic.
//
// Input (s_axis_*): commands from packet_decoder_v1, tdata = {code[1:0], a[31:0], b[31:0],
// feed[15:0]}, tuser = 1 for init (a, b = NUMERATOR_X, NUMERATOR_Y).
//   - An init command is accepted only while the executor is idle (exec_idle) and no prepared
//     segment is waiting, so it never changes the timing of a move that is queued or running.
//   - A motion command is prepared:
//       dominant axis  = X if |steps_x| >= |steps_y| else Y
//       period P       = NUMERATOR_dom / feed  (integer division), or FEED0_PERIOD when feed = 0,
//                        then raised to min_period (the fastest rate the step pulse generators can
//                        produce with the current STEP high + low settings)
//       total T        = P * N, N = |steps_dom|: the segment lasts T clocks
//       tmn[a]         = T - |steps_a| for every axis (the DDA's wrap constant)
//     The divide and the multiply are sequential (one bit per clock): no divider or wide multiplier
//     on a clocked path. Latency: m_axis_tvalid rises PREP_LATENCY = 68 clocks after the clock
//     edge that accepts the command (DIV 33, CLAMP 1, MUL 33, SUB 1), whatever the values.
// Output (m_axis_*): one prepared segment, held until accepted.
`default_nettype none

module segment_prep #(
    parameter N_AXES            = 4,
    parameter FEED0_PERIOD      = 62_500,
    parameter DEFAULT_NUMERATOR = 18_750_000   // CLK_HZ * 60 / 160 steps/mm at 50 MHz
) (
    input wire clk,
    input wire rst,

    input  wire [81:0] s_axis_tdata,
    input  wire        s_axis_tuser,
    input  wire        s_axis_tvalid,
    output wire        s_axis_tready,

    input wire        exec_idle,
    input wire [31:0] min_period,

    output wire [         1:0] m_axis_code,
    output wire [  N_AXES-1:0] m_axis_dir,      // 1 = positive direction
    output wire [32*N_AXES-1:0] m_axis_steps,   // |steps| per axis
    output wire [64*N_AXES-1:0] m_axis_tmn,     // T - |steps| per axis
    output wire [        63:0] m_axis_total,    // T, segment length in clocks
    output wire [        31:0] m_axis_period,   // P, dominant step period in clocks
    output wire [        15:0] m_axis_feed,     // feed as received (status only)
    output wire                m_axis_tvalid,
    input  wire                m_axis_tready,

    output wire [31:0] numerator_x,
    output wire [31:0] numerator_y,
    output wire        init_applied,  // 1-clock strobe
    output wire        busy           // a motion command is being prepared or waiting
);

  localparam [2:0] S_IDLE = 3'd0, S_DIV = 3'd1, S_CLAMP = 3'd2, S_MUL = 3'd3, S_SUB = 3'd4,
                   S_OUT = 3'd5;

  reg [2:0] state_reg;
  reg [31:0] num_x_reg, num_y_reg;
  reg        init_applied_reg;

  reg [1:0] code_reg;
  reg [1:0] dir_xy_reg;
  reg [31:0] abs_x_reg, abs_y_reg;
  reg [15:0] feed_reg;

  // restoring divider
  reg [31:0] dividend_reg;  // shifts left; its MSB enters the remainder
  reg [15:0] rem_reg;  // remainder < feed
  reg [31:0] quot_reg;
  reg [5:0]  iter_reg;

  // shift-add multiplier
  reg [31:0] mplier_reg;
  reg [63:0] mcand_reg;
  reg [63:0] total_reg;

  reg [64*N_AXES-1:0] tmn_reg;

  wire [31:0] steps_x_in = s_axis_tdata[79:48];
  wire [31:0] steps_y_in = s_axis_tdata[47:16];
  wire [31:0] abs_x_in = steps_x_in[31] ? (~steps_x_in + 32'd1) : steps_x_in;
  wire [31:0] abs_y_in = steps_y_in[31] ? (~steps_y_in + 32'd1) : steps_y_in;
  wire        x_dom = (abs_x_reg >= abs_y_reg);
  wire [31:0] n_dom = x_dom ? abs_x_reg : abs_y_reg;

  wire [16:0] rem_shift = {rem_reg, dividend_reg[31]};
  wire [15:0] rem_sub = rem_shift[15:0] - feed_reg;  // used only when rem_shift >= feed
  wire        rem_ge = (rem_shift >= {1'b0, feed_reg});

  wire accept_init = (state_reg == S_IDLE) && s_axis_tuser && exec_idle;
  wire accept_motion = (state_reg == S_IDLE) && !s_axis_tuser;

  // |steps| per axis as sent downstream (v1 drives X and Y only)
  wire [32*N_AXES-1:0] steps_all;
  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_steps
      if (a == 0) begin : g_x
        assign steps_all[32*a+:32] = abs_x_reg;
      end else if (a == 1) begin : g_y
        assign steps_all[32*a+:32] = abs_y_reg;
      end else begin : g_other
        assign steps_all[32*a+:32] = 32'd0;
      end
    end
  endgenerate

  integer i;
  always @(posedge clk) begin
    init_applied_reg <= 1'b0;
    case (state_reg)
      S_IDLE: begin
        if (s_axis_tvalid && accept_init) begin
          num_x_reg        <= s_axis_tdata[79:48];
          num_y_reg        <= s_axis_tdata[47:16];
          init_applied_reg <= 1'b1;
        end else if (s_axis_tvalid && accept_motion) begin
          code_reg     <= s_axis_tdata[81:80];
          dir_xy_reg   <= {~steps_y_in[31], ~steps_x_in[31]};
          abs_x_reg    <= abs_x_in;
          abs_y_reg    <= abs_y_in;
          feed_reg     <= s_axis_tdata[15:0];
          rem_reg      <= 16'd0;
          quot_reg     <= 32'd0;
          iter_reg     <= 6'd0;
          // dividend chosen one clock later, once the dominant axis is known
          state_reg    <= S_DIV;
        end
      end
      S_DIV: begin
        if (iter_reg == 6'd0) begin
          dividend_reg <= x_dom ? num_x_reg : num_y_reg;
          iter_reg     <= 6'd1;
        end else begin
          dividend_reg <= {dividend_reg[30:0], 1'b0};
          rem_reg      <= rem_ge ? rem_sub : rem_shift[15:0];
          quot_reg     <= {quot_reg[30:0], rem_ge};
          iter_reg     <= iter_reg + 6'd1;
          if (iter_reg == 6'd32) state_reg <= S_CLAMP;
        end
      end
      S_CLAMP: begin
        // feed 0: fixed period; the quotient of a divide by zero is discarded
        if (feed_reg == 16'd0) quot_reg <= (FEED0_PERIOD < min_period) ? min_period : FEED0_PERIOD;
        else if (quot_reg < min_period) quot_reg <= min_period;
        mplier_reg <= n_dom;
        total_reg  <= 64'd0;
        state_reg  <= S_MUL;
        iter_reg   <= 6'd0;
      end
      S_MUL: begin
        if (iter_reg == 6'd0) begin
          mcand_reg <= {32'd0, quot_reg};
          iter_reg  <= 6'd1;
        end else begin
          if (mplier_reg[0]) total_reg <= total_reg + mcand_reg;
          mplier_reg <= {1'b0, mplier_reg[31:1]};
          mcand_reg  <= {mcand_reg[62:0], 1'b0};
          iter_reg   <= iter_reg + 6'd1;
          if (iter_reg == 6'd32) state_reg <= S_SUB;
        end
      end
      S_SUB: begin
        for (i = 0; i < N_AXES; i = i + 1)
          tmn_reg[64*i+:64] <= total_reg - {32'd0, steps_all[32*i+:32]};
        state_reg <= S_OUT;
      end
      S_OUT: begin
        if (m_axis_tready) state_reg <= S_IDLE;
      end
      default: state_reg <= S_IDLE;
    endcase

    if (rst) begin
      state_reg        <= S_IDLE;
      num_x_reg        <= DEFAULT_NUMERATOR;
      num_y_reg        <= DEFAULT_NUMERATOR;
      init_applied_reg <= 1'b0;
      code_reg         <= 2'd0;
      dir_xy_reg       <= 2'b00;
      abs_x_reg        <= 32'd0;
      abs_y_reg        <= 32'd0;
      feed_reg         <= 16'd0;
      dividend_reg     <= 32'd0;
      rem_reg          <= 16'd0;
      quot_reg         <= 32'd0;
      iter_reg         <= 6'd0;
      mplier_reg       <= 32'd0;
      mcand_reg        <= 64'd0;
      total_reg        <= 64'd0;
      tmn_reg          <= {64 * N_AXES{1'b0}};
    end
  end

  wire [N_AXES-1:0] dir_all;
  generate
    if (N_AXES > 2) begin : g_dir_wide
      assign dir_all = {{(N_AXES - 2) {1'b0}}, dir_xy_reg};
    end else begin : g_dir_narrow
      assign dir_all = dir_xy_reg[N_AXES-1:0];
    end
  endgenerate

  assign s_axis_tready = accept_motion || accept_init;
  assign m_axis_code   = code_reg;
  assign m_axis_dir    = dir_all;
  assign m_axis_steps  = steps_all;
  assign m_axis_tmn    = tmn_reg;
  assign m_axis_total  = total_reg;
  assign m_axis_period = quot_reg;
  assign m_axis_feed   = feed_reg;
  assign m_axis_tvalid = (state_reg == S_OUT);
  assign numerator_x   = num_x_reg;
  assign numerator_y   = num_y_reg;
  assign init_applied  = init_applied_reg;
  assign busy          = (state_reg != S_IDLE);

endmodule

`default_nettype wire
