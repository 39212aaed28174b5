// step_config: cnc_core's step timing: per axis STEP high, STEP low, DIR setup and DIR hold in
// clocks as segment_prep and segment_executor use them (docs/timing.md), and the minimum dominant
// period they allow.
//
// Contract
//   cfg_wr, cfg_addr, cfg_wdata   write port, address axis * 4 + field (0 STEP high, 1 STEP low,
//                    2 DIR setup, 3 DIR hold); an address of an axis >= N_AXES is ignored.
//   frame_wr, frame_axis, frame_data   a CONFIG_AXIS frame (frame_decoder's cfg_*): the axis's four
//                    fields {high, low, setup, hold}, 16 bits each; ignored for axis >= N_AXES.
//                    Both writes go to a shadow set; the port wins over a frame on the same clock
//                    and field.
//   quiet            the FIFO is empty and nothing is prepared or running: the active set takes the
//                    shadow set on every edge with quiet.
//   cfg_high, cfg_low, cfg_setup, cfg_hold   the active set, axis a in [16*a+:16]; after rst both
//                    sets hold STEP_HIGH, STEP_LOW, DIR_SETUP, DIR_HOLD for every axis.
//   min_period       max over the axes of max(STEP high, 1) + max(STEP low, 1), at least 2: the
//                    fastest dominant period the pulse generators follow. A scanner takes one axis a
//                    clock (no comparator chain across axes), so a change of the active set reaches
//                    min_period within 2 * N_AXES + 2 clocks (segment_prep reads it 34 clocks after
//                    it accepts a move, and the active set changes only while it is idle). After
//                    rst: STEP_HIGH + STEP_LOW.
// FIXED = 1 (cnc_core's STEP_CFG = 0): no shadow or active set and no scanner; the outputs are the
// parameters (min_period counts a setting of 0 as 1 clock, as step_pulse does) and the write
// ports are not read.
// N_AXES 1..15, FIXED 0 or 1, each timing parameter 0..65535; an illegal value instantiates a
// module named step_config_illegal_<rule>, which does not exist.
`default_nettype none
`include "fpgacnc_spec.vh"

module step_config #(
    parameter N_AXES    = `FPGACNC_DEF_N_AXES,
    parameter STEP_HIGH = `FPGACNC_DEF_STEP_HIGH,
    parameter STEP_LOW  = `FPGACNC_DEF_STEP_LOW,
    parameter DIR_SETUP = `FPGACNC_DEF_DIR_SETUP,
    parameter DIR_HOLD  = `FPGACNC_DEF_DIR_HOLD,
    parameter FIXED     = 0  // 1: the timing fixed at the parameters
) (
    input wire clk,
    input wire rst,

    input wire        cfg_wr,
    input wire [ 7:0] cfg_addr,
    input wire [15:0] cfg_wdata,

    input wire        frame_wr,
    input wire [ 7:0] frame_axis,
    input wire [63:0] frame_data,

    input wire quiet,

    output wire [16*N_AXES-1:0] cfg_high,
    output wire [16*N_AXES-1:0] cfg_low,
    output wire [16*N_AXES-1:0] cfg_setup,
    output wire [16*N_AXES-1:0] cfg_hold,
    output wire [         31:0] min_period
);

  generate
    if (N_AXES < 1 || N_AXES > 15) begin : g_bad_n_axes
      step_config_illegal_N_AXES_not_1_to_15 u_err ();
    end
    if (FIXED != 0 && FIXED != 1) begin : g_bad_fixed
      step_config_illegal_FIXED_not_0_or_1 u_err ();
    end
    if (STEP_HIGH < 0 || STEP_HIGH > 65535 || STEP_LOW < 0 || STEP_LOW > 65535 ||
        DIR_SETUP < 0 || DIR_SETUP > 65535 || DIR_HOLD < 0 || DIR_HOLD > 65535)
    begin : g_bad_timing
      step_config_illegal_timing_not_0_to_65535 u_err ();
    end
  endgenerate

  localparam AXW = (N_AXES > 1) ? $clog2(N_AXES) : 1;
  localparam integer AX_LAST_I = N_AXES - 1;
  localparam [AXW-1:0] AX_LAST = AX_LAST_I[AXW-1:0];
  localparam integer NAX_I = N_AXES;
  localparam [7:0] NAX8 = NAX_I[7:0];
  // fixed timing: a setting of 0 counts as 1 clock, as in step_pulse
  localparam integer FIX_PERIOD_I = ((STEP_HIGH == 0) ? 1 : STEP_HIGH) + ((STEP_LOW == 0) ? 1 : STEP_LOW);
  localparam [31:0] FIX_PERIOD = FIX_PERIOD_I;

  generate
    if (FIXED == 0) begin : g_cfg
      reg [16*N_AXES-1:0] shadow_high_reg, shadow_low_reg, shadow_setup_reg, shadow_hold_reg;
      reg [16*N_AXES-1:0] cfg_high_reg, cfg_low_reg, cfg_setup_reg, cfg_hold_reg;
      reg [31:0] min_period_reg;
      reg [AXW-1:0] pm_idx_reg, pm_idx_d_reg;
      reg [16:0] pm_sum_reg, pm_run_reg;
      // step_pulse treats a setting of 0 as 1 clock: count it so here too.
      wire [15:0] pm_high_raw = cfg_high_reg[16*pm_idx_reg+:16];
      wire [15:0] pm_low_raw = cfg_low_reg[16*pm_idx_reg+:16];
      wire [15:0] pm_high = (pm_high_raw == 16'd0) ? 16'd1 : pm_high_raw;
      wire [15:0] pm_low = (pm_low_raw == 16'd0) ? 16'd1 : pm_low_raw;
      wire [16:0] pm_cand = (pm_idx_d_reg == {AXW{1'b0}} || pm_sum_reg > pm_run_reg) ? pm_sum_reg
                                                                                     : pm_run_reg;

      wire [AXW-1:0] frame_ax = frame_axis[AXW-1:0];

      always @(posedge clk) begin
        if (frame_wr && frame_axis < NAX8) begin
          shadow_high_reg[16*frame_ax+:16]  <= frame_data[63:48];
          shadow_low_reg[16*frame_ax+:16]   <= frame_data[47:32];
          shadow_setup_reg[16*frame_ax+:16] <= frame_data[31:16];
          shadow_hold_reg[16*frame_ax+:16]  <= frame_data[15:0];
        end
        if (cfg_wr && {2'b00, cfg_addr[7:2]} < NAX8) begin
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
      assign cfg_high   = cfg_high_reg;
      assign cfg_low    = cfg_low_reg;
      assign cfg_setup  = cfg_setup_reg;
      assign cfg_hold   = cfg_hold_reg;
      assign min_period = min_period_reg;
    end else begin : g_fixed
      assign cfg_high   = {N_AXES{STEP_HIGH[15:0]}};
      assign cfg_low    = {N_AXES{STEP_LOW[15:0]}};
      assign cfg_setup  = {N_AXES{DIR_SETUP[15:0]}};
      assign cfg_hold   = {N_AXES{DIR_HOLD[15:0]}};
      assign min_period = FIX_PERIOD;
      wire unused_cfg = &{1'b0, clk, rst, cfg_wr, cfg_addr, cfg_wdata, frame_wr, frame_axis,
                          frame_data, quiet};
    end
  endgenerate

endmodule

`default_nettype wire
