// dda_profile: exact DDA of one axis of a profiled segment (profile_gen is the master;
// docs/timing.md "Profiled segments", docs/motion.md).
//
// The axis makes n steps while the dominant axis makes n_dom (M = n_dom*2^48). It keeps
// V_i = V*n (UQ23.48, < 2^71: V < 2^47, n < 2^24) and a remainder r = R - M with R = U*n mod M
// (r in [-M, 0), 73-bit two's complement). Per tick: s = r + V_i; s >= 0: step, r = s - M (only
// the integer part changes: a 25-bit subtract after the sign); else r = s. So after clock c the
// axis has made exactly floor(U(c)*n / M) steps. V_i follows the master's op of the tick
// (profile_gen runs one clock ahead): INC V_i += A*n, DEC V_i -= A*n, CRU V_i = V_cruise*n,
// EXIT V_i = V_exit*n (all exact products from segment_prep).
// load (wins over a tick on the same edge; the tick's step is still issued, being combinational):
// r = -M, V_i = V_entry*n. step is combinational from the registers and tick: the executor's
// step_pulse raises STEP on the next edge.
`default_nettype none

module dda_profile (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [23:0] n_dom,
    input wire [70:0] v0,     // V_entry * n
    input wire [70:0] vc,     // V_cruise * n
    input wire [70:0] vx,     // V_exit * n
    input wire [55:0] acc,    // A * n

    input wire       tick,
    input wire [1:0] op,      // profile_gen op of this tick

    output wire step
);

  localparam [1:0] OP_INC = 2'd0, OP_DEC = 2'd1, OP_CRU = 2'd2;

  reg [72:0] r_reg;
  reg [70:0] v_reg, vc_reg, vx_reg;
  reg [55:0] a_reg;
  reg [23:0] n_reg;

  // s = r + V_i as a 36-bit low half and the high half for carry 0 and 1 (carry select): the step
  // decision (s's sign) goes on to the executor and step_pulse, so its chain is cut in two. Formed
  // only in tick clocks (x, a don't-care, in others: r_reg and step read it only with tick), so a
  // simulator skips it while the axis is idle; synthesis keeps the plain sum.
  reg [72:0] s;
  reg        wrap;
  reg [24:0] s_hi_m;
  always @(*) begin : sum
    reg [36:0] s_lo, s_h0;
    /* verilator lint_off UNUSEDSIGNAL */
    reg [37:0] s_h1;  // [37:1]: the high half + 1
    /* verilator lint_on UNUSEDSIGNAL */
    s      = {73{1'bx}};
    wrap   = 1'bx;
    s_hi_m = {25{1'bx}};
    s_lo   = {37{1'bx}};
    s_h0   = {37{1'bx}};
    s_h1   = {38{1'bx}};
    if (tick) begin
      s_lo   = {1'b0, r_reg[35:0]} + {1'b0, v_reg[35:0]};
      s_h0   = r_reg[72:36] + {2'b00, v_reg[70:36]};
      s_h1   = {r_reg[72:36], 1'b1} + {2'b00, v_reg[70:36], 1'b1};
      s      = {s_lo[36] ? s_h1[37:1] : s_h0, s_lo[35:0]};
      wrap   = !s[72];
      s_hi_m = s[72:48] - {1'b0, n_reg};
    end
  end

  always @(posedge clk) begin
    if (load) begin
      r_reg  <= {1'b1, ~n_dom + 24'd1, 48'd0};  // -M (n_dom >= 1)
      v_reg  <= v0;
      vc_reg <= vc;
      vx_reg <= vx;
      a_reg  <= acc;
      n_reg  <= n_dom;
    end else if (tick) begin
      r_reg <= wrap ? {s_hi_m, s[47:0]} : s;
      case (op)
        OP_INC:  v_reg <= v_reg + {15'd0, a_reg};
        OP_DEC:  v_reg <= v_reg - {15'd0, a_reg};
        OP_CRU:  v_reg <= vc_reg;
        default: v_reg <= vx_reg;
      endcase
    end
    if (rst) begin
      r_reg  <= 73'd0;
      v_reg  <= 71'd0;
      vc_reg <= 71'd0;
      vx_reg <= 71'd0;
      a_reg  <= 56'd0;
      n_reg  <= 24'd0;
    end
  end

  assign step = tick && wrap;

endmodule

`default_nettype wire
