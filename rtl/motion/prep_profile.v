// prep_profile: segment_prep's LINE_PROFILE arithmetic (docs/timing.md "Profiled segments"): the
// per-axis products of the speeds and the acceleration by n_a, and profile_gen's first master
// update. segment_prep sequences it (states PMUL, then PINIT) and holds the prepared segment.
//
// load (the clock segment_prep takes a segment entry): the entry's V_entry, V_cruise, V_exit, A
// and D are latched (whatever the entry's kind; only a PROFILE segment reads them).
// Products (mul_run, iter = 0..24): iteration 0 loads the multiplicands and the per-axis
// multipliers n_a = abs[32*a+:24]; iterations 1..24 add bit iter-1 of every n_a (shift-add, all axes
// and all four products in parallel: 4*N_AXES adders of at most 71 bits). After iteration 24:
// v0 = V_entry*n_a, vc = V_cruise*n_a, vx = V_exit*n_a (71 bits), acc = A*n_a (56 bits) per axis.
// init (PINIT, one clock): vcma = V_cruise - A, vxpa = V_exit + A, and U(1) = V_entry with V(1)
// and op(1) from V(0) = V_entry, "decelerating" = (D == 0) (docs/timing.md).
// The outputs are registers, held until the next load / mul_run / init.
`default_nettype none

module prep_profile #(
    parameter N_AXES = 4
) (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [46:0] in_ve,     // V_entry
    input wire [46:0] in_vc,     // V_cruise
    input wire [46:0] in_vx,     // V_exit
    input wire [31:0] in_accel,  // A
    input wire [31:0] in_d,      // D (decel_at)

    input wire                  mul_run,  // segment_prep in PMUL
    input wire [           5:0] iter,     // its iteration
    /* verilator lint_off UNUSEDSIGNAL */
    input wire [32*N_AXES-1:0] abs,       // |steps| per axis (n_a: the low 24 bits)
    /* verilator lint_on UNUSEDSIGNAL */
    input wire                  init,     // PINIT

    output wire [          46:0] u1,        // U(1) = V_entry
    output wire [          46:0] v1,        // V(1)
    output wire [           1:0] op1,       // op(1)
    output wire [          31:0] accel,     // A
    output wire [          46:0] vcruise,
    output wire [          46:0] vexit,
    output wire [          47:0] vcma,      // V_cruise - A
    output wire [          47:0] vxpa,      // V_exit + A
    output wire [          31:0] decel_at,  // D
    output wire [71*N_AXES-1:0] v0,        // per axis V_entry * n_a
    output wire [71*N_AXES-1:0] vc,        // V_cruise * n_a
    output wire [71*N_AXES-1:0] vx,        // V_exit * n_a
    output wire [56*N_AXES-1:0] acc        // A * n_a
);

  generate
    if (N_AXES < 1) begin : g_bad_n_axes
      prep_profile_illegal_N_AXES_below_1 u_err ();
    end
  endgenerate

  localparam [1:0] OP_INC = 2'd0, OP_DEC = 2'd1, OP_CRU = 2'd2, OP_EXIT = 2'd3;
  reg [46:0] ve_reg, vc_reg, vx_reg;
  reg [31:0] pa_reg, d_reg;
  reg [46:0] v1_reg;
  reg [1:0] op1_reg;
  reg [47:0] vcma_reg, vxpa_reg;
  reg [70:0] mc_ve_reg, mc_vc_reg, mc_vx_reg;  // shifted multiplicands
  reg [55:0] mc_a_reg;
  reg [24*N_AXES-1:0] pm_reg;  // per-axis multipliers (n_a), shifted right
  reg [71*N_AXES-1:0] p_v0_reg, p_vc_reg, p_vx_reg;
  reg [56*N_AXES-1:0] p_a_reg;

  always @(posedge clk) begin
    if (load) begin
      ve_reg <= in_ve;
      vc_reg <= in_vc;
      vx_reg <= in_vx;
      pa_reg <= in_accel;
      d_reg  <= in_d;
    end
    if (init) begin
      vcma_reg <= {1'b0, vc_reg} - {16'd0, pa_reg};
      vxpa_reg <= {1'b0, vx_reg} + {16'd0, pa_reg};
      if (d_reg == 32'd0) begin
        if ({1'b0, ve_reg} >= {1'b0, vx_reg} + {16'd0, pa_reg}) begin
          v1_reg  <= ve_reg - {15'd0, pa_reg};
          op1_reg <= OP_DEC;
        end else begin
          v1_reg  <= vx_reg;
          op1_reg <= OP_EXIT;
        end
      end else begin
        if ({1'b0, ve_reg} + {16'd0, pa_reg} <= {1'b0, vc_reg}) begin
          v1_reg  <= ve_reg + {15'd0, pa_reg};
          op1_reg <= OP_INC;
        end else begin
          v1_reg  <= vc_reg;
          op1_reg <= OP_CRU;
        end
      end
    end
    if (rst) begin
      ve_reg   <= 47'd0;
      vc_reg   <= 47'd0;
      vx_reg   <= 47'd0;
      pa_reg   <= 32'd0;
      d_reg    <= 32'd0;
      v1_reg   <= 47'd0;
      op1_reg  <= OP_CRU;
      vcma_reg <= 48'd0;
      vxpa_reg <= 48'd0;
    end
  end

  // The multipliers' datapaths, each register written by one guarded assignment: Verilator then
  // updates it in place and skips the block on the clocks it is idle (docs/architecture.md
  // "Simulation speed").
  always @(posedge clk) begin : pmul_seq
    reg [71*N_AXES-1:0] v0_n, vc_n, vx_n;
    reg [56*N_AXES-1:0] a_n;
    reg [24*N_AXES-1:0] pm_n;
    reg [70:0] mce_n, mcc_n, mcx_n;
    reg [55:0] mca_n;
    integer k;
    if (rst || mul_run) begin
      v0_n  = {71 * N_AXES{1'b0}};
      vc_n  = {71 * N_AXES{1'b0}};
      vx_n  = {71 * N_AXES{1'b0}};
      a_n   = {56 * N_AXES{1'b0}};
      pm_n  = {24 * N_AXES{1'b0}};
      mce_n = 71'd0;
      mcc_n = 71'd0;
      mcx_n = 71'd0;
      mca_n = 56'd0;
      if (!rst && iter == 6'd0) begin
        mce_n = {24'd0, ve_reg};
        mcc_n = {24'd0, vc_reg};
        mcx_n = {24'd0, vx_reg};
        mca_n = {24'd0, pa_reg};
        for (k = 0; k < N_AXES; k = k + 1) pm_n[24*k+:24] = abs[32*k+:24];
      end else if (!rst) begin
        for (k = 0; k < N_AXES; k = k + 1) begin
          v0_n[71*k+:71] = p_v0_reg[71*k+:71];
          vc_n[71*k+:71] = p_vc_reg[71*k+:71];
          vx_n[71*k+:71] = p_vx_reg[71*k+:71];
          a_n[56*k+:56]  = p_a_reg[56*k+:56];
          if (pm_reg[24*k]) begin
            v0_n[71*k+:71] = p_v0_reg[71*k+:71] + mc_ve_reg;
            vc_n[71*k+:71] = p_vc_reg[71*k+:71] + mc_vc_reg;
            vx_n[71*k+:71] = p_vx_reg[71*k+:71] + mc_vx_reg;
            a_n[56*k+:56]  = p_a_reg[56*k+:56] + mc_a_reg;
          end
          pm_n[24*k+:24] = {1'b0, pm_reg[24*k+1+:23]};
        end
        mce_n = {mc_ve_reg[69:0], 1'b0};
        mcc_n = {mc_vc_reg[69:0], 1'b0};
        mcx_n = {mc_vx_reg[69:0], 1'b0};
        mca_n = {mc_a_reg[54:0], 1'b0};
      end
      p_v0_reg  <= v0_n;
      p_vc_reg  <= vc_n;
      p_vx_reg  <= vx_n;
      p_a_reg   <= a_n;
      pm_reg    <= pm_n;
      mc_ve_reg <= mce_n;
      mc_vc_reg <= mcc_n;
      mc_vx_reg <= mcx_n;
      mc_a_reg  <= mca_n;
    end
  end

  assign u1       = ve_reg;
  assign v1       = v1_reg;
  assign op1      = op1_reg;
  assign accel    = pa_reg;
  assign vcruise  = vc_reg;
  assign vexit    = vx_reg;
  assign vcma     = vcma_reg;
  assign vxpa     = vxpa_reg;
  assign decel_at = d_reg;
  assign v0       = p_v0_reg;
  assign vc       = p_vc_reg;
  assign vx       = p_vx_reg;
  assign acc      = p_a_reg;

endmodule

`default_nettype wire
