// segment_executor: runs prepared linear segments on N_AXES axes at a constant rate.
//
// Input (s_axis_*): one segment from segment_prep: code, per-axis direction and |steps|, the
// per-axis DDA constant T - |steps| and the length T in clocks. Accepted only when idle
// (s_axis_tready = idle state).
// Sequence for a segment, in clocks:
//   accept edge A. T = 0 (no steps): done at once, seg_done strobes in the next clock.
//   If an axis that moves must change DIR: wait until that axis's DIR hold has elapsed since its
//   last STEP rising edge (HOLD), write DIR (edge D), wait the largest DIR setup of the changed
//   axes (run starts at edge R = D + max(setup, 1)). Otherwise run starts at R = A.
//   RUN: clock c = 1..T after R is tick c of every axis's dda_linear; a step on tick c raises STEP
//   at edge R + c (step_pulse adds one register). seg_start is high during tick 1, laser is high
//   from edge R to edge R + T for codes 1..3 (G1/G2/G3), never for code 0 (G0). After tick T the
//   executor is idle again and seg_done strobes for one clock.
// So the k-th STEP rising edge of an axis with n steps is at R + ceil(k*T/n): all axes start at R,
// every axis's last step is at R + T, and each step is within one clock of R + k*T/n.
// position: signed step count per axis, updated on the edge STEP rises.
`default_nettype none

module segment_executor #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input  wire [         1:0] s_axis_code,
    input  wire [  N_AXES-1:0] s_axis_dir,
    input  wire [32*N_AXES-1:0] s_axis_steps,
    input  wire [64*N_AXES-1:0] s_axis_tmn,
    input  wire [        63:0] s_axis_total,
    input  wire                s_axis_tvalid,
    output wire                s_axis_tready,

    input wire [16*N_AXES-1:0] cfg_step_high,
    input wire [16*N_AXES-1:0] cfg_step_low,
    input wire [16*N_AXES-1:0] cfg_dir_setup,
    input wire [16*N_AXES-1:0] cfg_dir_hold,

    output wire [N_AXES-1:0] step,
    output wire [N_AXES-1:0] dir,
    output wire              laser,

    output wire                 busy,       // a segment is in progress (HOLD, SETUP or RUN)
    output wire                 idle,       // not busy and every STEP pulse finished
    output wire                 running,    // RUN: ticks are being issued
    output wire                 seg_start,  // high during tick 1 of a segment
    output wire                 seg_done,   // 1-clock strobe after a segment's last tick
    output wire [32*N_AXES-1:0] position,
    output wire                 violation   // 1-clock strobe: a step came before STEP low time
);

  localparam [1:0] S_IDLE = 2'd0, S_HOLD = 2'd1, S_SETUP = 2'd2, S_RUN = 2'd3;

  reg [1:0] state_reg;
  reg [1:0] code_reg;
  reg [N_AXES-1:0] dir_new_reg;
  reg [N_AXES-1:0] change_reg;
  reg [15:0] setup_cnt_reg;
  reg laser_reg;
  reg seg_start_reg;
  reg seg_done_reg;
  reg [32*N_AXES-1:0] pos_reg;

  wire [N_AXES-1:0] dda_step, dda_done_next, pulse_idle, pulse_hold_ok, pulse_violation;
  wire [N_AXES-1:0] moving;

  wire accept = (state_reg == S_IDLE) && s_axis_tvalid;
  wire tick = (state_reg == S_RUN);
  wire all_done_next = &dda_done_next;
  wire hold_clear = ((change_reg & ~pulse_hold_ok) == {N_AXES{1'b0}});
  wire dir_wr = (state_reg == S_HOLD) && hold_clear;

  // Largest DIR setup among the axes that change direction.
  reg [15:0] setup_max;
  integer j;
  always @(*) begin
    setup_max = 16'd0;
    for (j = 0; j < N_AXES; j = j + 1)
      if (change_reg[j] && cfg_dir_setup[16*j+:16] > setup_max) setup_max = cfg_dir_setup[16*j+:16];
  end

  genvar a;
  generate
    for (a = 0; a < N_AXES; a = a + 1) begin : g_axis
      assign moving[a] = (s_axis_steps[32*a+:32] != 32'd0);

      dda_linear u_dda (
          .clk      (clk),
          .rst      (rst),
          .load     (accept),
          .steps    (s_axis_steps[32*a+:32]),
          .tmn      (s_axis_tmn[64*a+:64]),
          .tick     (tick),
          .step     (dda_step[a]),
          .done_next(dda_done_next[a])
      );

      step_pulse u_pulse (
          .clk      (clk),
          .rst      (rst),
          .cfg_high (cfg_step_high[16*a+:16]),
          .cfg_low  (cfg_step_low[16*a+:16]),
          .cfg_hold (cfg_dir_hold[16*a+:16]),
          .step_req (dda_step[a]),
          .dir_in   (dir_new_reg[a]),
          .dir_wr   (dir_wr && change_reg[a]),
          .step     (step[a]),
          .dir      (dir[a]),
          .idle     (pulse_idle[a]),
          .hold_ok  (pulse_hold_ok[a]),
          .violation(pulse_violation[a])
      );

      always @(posedge clk) begin
        if (dda_step[a])
          pos_reg[32*a+:32] <= dir[a] ? pos_reg[32*a+:32] + 32'd1 : pos_reg[32*a+:32] - 32'd1;
        if (rst) pos_reg[32*a+:32] <= 32'd0;
      end
    end
  endgenerate

  always @(posedge clk) begin
    seg_start_reg <= 1'b0;
    seg_done_reg  <= 1'b0;
    case (state_reg)
      S_IDLE: begin
        if (accept) begin
          code_reg    <= s_axis_code;
          dir_new_reg <= s_axis_dir;
          change_reg  <= (s_axis_dir ^ dir) & moving;
          if (s_axis_total == 64'd0) begin
            seg_done_reg <= 1'b1;
          end else if (((s_axis_dir ^ dir) & moving) != {N_AXES{1'b0}}) begin
            state_reg <= S_HOLD;
          end else begin
            state_reg     <= S_RUN;
            seg_start_reg <= 1'b1;
            laser_reg     <= (s_axis_code != 2'd0);
          end
        end
      end
      S_HOLD: begin
        if (hold_clear) begin
          setup_cnt_reg <= setup_max;
          state_reg     <= S_SETUP;
        end
      end
      S_SETUP: begin
        if (setup_cnt_reg <= 16'd1) begin
          state_reg     <= S_RUN;
          seg_start_reg <= 1'b1;
          laser_reg     <= (code_reg != 2'd0);
        end else begin
          setup_cnt_reg <= setup_cnt_reg - 16'd1;
        end
      end
      S_RUN: begin
        if (all_done_next) begin
          state_reg    <= S_IDLE;
          laser_reg    <= 1'b0;
          seg_done_reg <= 1'b1;
        end
      end
      default: state_reg <= S_IDLE;
    endcase

    if (rst) begin
      state_reg     <= S_IDLE;
      code_reg      <= 2'd0;
      dir_new_reg   <= {N_AXES{1'b0}};
      change_reg    <= {N_AXES{1'b0}};
      setup_cnt_reg <= 16'd0;
      laser_reg     <= 1'b0;
      seg_start_reg <= 1'b0;
      seg_done_reg  <= 1'b0;
    end
  end

  assign s_axis_tready = (state_reg == S_IDLE);
  assign laser         = laser_reg;
  assign busy          = (state_reg != S_IDLE);
  assign idle          = (state_reg == S_IDLE) && (&pulse_idle);
  assign running       = (state_reg == S_RUN);
  assign seg_start     = seg_start_reg;
  assign seg_done      = seg_done_reg;
  assign position      = pos_reg;
  assign violation     = |pulse_violation;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh, k-induction). Assumes only reset in the first clock.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  always @(*)
    if (f_past_valid) begin
      // Laser is low while the executor is idle (or waiting for DIR hold/setup), and during a
      // rapid (code 0) segment: it can only be high while RUN executes a segment of code 1..3.
      if (state_reg != S_RUN) assert (!laser);
      if (code_reg == 2'd0) assert (!laser);
    end
`endif

endmodule

`default_nettype wire
