// profile_gen: the master of a profiled segment: path position U and velocity V along the dominant
// axis, one update per tick (docs/protocol.md "LINE_PROFILE", docs/timing.md "Profiled segments").
//
// Formats: U UQ24.48 dominant steps (72 bits), V UQ0.47 in units of 2^-48 dominant steps per clock
// (V < 2^47), A u32 in 2^-48 steps per clock^2, D and n_dom in whole dominant steps.
// Recurrence (clock c = 0, 1, ... of the segment; V constant within a clock):
//   U(c+1) = U(c) + V(c)
//   V(c+1) = U(c+1) >= D*2^48 ? (V(c) >= V_exit + A ? V(c) - A : V_exit)      op DEC / EXIT
//                             : (V(c) + A <= V_cruise ? V(c) + A : V_cruise)  op INC / CRU
// Pipelining: this block runs one clock ahead of the per-axis DDAs (dda_profile). During tick j
// (j = 1, 2, ...) it holds U(j), V(j) and op(j) (the change V(j-1) -> V(j)); the axes hold their
// remainders at clock j-1 and V_i(j-1) = V(j-1)*n_i, step from those in tick j, and apply op(j)
// to V_i at the end of tick j. segment_prep computes U(1) = V_entry, V(1) and op(1) and loads them
// with `load`, so tick 1 can follow the load edge directly.
// last = U(j) >= n_dom*2^48: tick j is the segment's last; the axes reach their exact counts in
// it. A register (last_reg: the compare of the next U and n_dom, formed on every edge), so the
// executor's zero-gap chaining (last -> accept -> the next load) starts at a flip-flop.
// Precomputed by segment_prep: vcma = V_cruise - A (signed 48 bits; negative: never INC) and
// vxpa = V_exit + A. Per tick: one 72-bit add, the compare of its integer part with D (made from
// U(c)'s integer part for carry 0 and 1, in parallel with the add's 48-bit fraction), and a
// 4-way mux of V (the compares of V with vcma / vxpa are from registers, in parallel).
`default_nettype none

module profile_gen (
    input wire clk,
    input wire rst,

    input wire        load,
    input wire [46:0] u1,      // U(1) = V_entry (integer part 0)
    input wire [46:0] v1,      // V(1)
    input wire [ 1:0] op1,     // op(1)
    input wire [31:0] accel,   // A
    input wire [46:0] vcruise,
    input wire [46:0] vexit,
    input wire [47:0] vcma,    // V_cruise - A, two's complement
    input wire [47:0] vxpa,    // V_exit + A
    input wire [31:0] decel_at,  // D
    input wire [23:0] n_dom,

    input wire tick,

    output wire        last,
    output wire [ 1:0] op,
    output wire [46:0] v,       // V of the current tick (V(j) during tick j; V(1) after load)
    output wire [46:0] vcruise_q  // the loaded V_cruise
);

  localparam [1:0] OP_INC = 2'd0, OP_DEC = 2'd1, OP_CRU = 2'd2, OP_EXIT = 2'd3;

  reg [71:0] u_reg;
  reg [46:0] v_reg;
  reg [ 1:0] op_reg;
  reg [31:0] a_reg;
  reg [46:0] vc_reg, vx_reg;
  reg [47:0] vcma_reg, vxpa_reg;
  reg [31:0] d_reg;
  reg [23:0] n_reg;
  reg        last_reg;  // = (u_reg[71:48] >= n_reg) on every clock

  // U(c+1)'s integer part is U(c)'s or one more (V < 2^47): the decel compare is made for both
  // from registers, in parallel with the 48-bit fraction add, and its carry picks one (the same
  // result as comparing U(c+1) after the whole 72-bit add, without the add and compare in series).
  wire [48:0] frac_sum = {1'b0, u_reg[47:0]} + {2'b0, v_reg};
  wire [71:0] u_next = {u_reg[71:48] + {23'd0, frac_sum[48]}, frac_sum[47:0]};
  wire [23:0] u_int1 = u_reg[71:48] + 24'd1;
  wire        dec0 = ({8'd0, u_reg[71:48]} >= d_reg);
  wire        dec1 = ({8'd0, u_int1} >= d_reg);
  wire        dec = frac_sum[48] ? dec1 : dec0;
  wire        can_dec = ({1'b0, v_reg} >= vxpa_reg);
  wire        can_inc = !vcma_reg[47] && ({1'b0, v_reg} <= vcma_reg);
  // last of the next clock: U's integer part after a tick is u_int or u_int + 1 (frac_sum's carry)
  wire        ge0 = (u_reg[71:48] >= n_reg);

  always @(posedge clk) begin
    last_reg <= ge0;
    if (load) begin
      last_reg <= (n_dom == 24'd0);
      u_reg    <= {25'd0, u1};
      v_reg    <= v1;
      op_reg   <= op1;
      a_reg    <= accel;
      vc_reg   <= vcruise;
      vx_reg   <= vexit;
      vcma_reg <= vcma;
      vxpa_reg <= vxpa;
      d_reg    <= decel_at;
      n_reg    <= n_dom;
    end else if (tick) begin
      u_reg <= u_next;
      last_reg <= frac_sum[48] ? (u_int1 >= n_reg) : ge0;
      if (dec) begin
        if (can_dec) begin
          v_reg  <= v_reg - {15'd0, a_reg};
          op_reg <= OP_DEC;
        end else begin
          v_reg  <= vx_reg;
          op_reg <= OP_EXIT;
        end
      end else begin
        if (can_inc) begin
          v_reg  <= v_reg + {15'd0, a_reg};
          op_reg <= OP_INC;
        end else begin
          v_reg  <= vc_reg;
          op_reg <= OP_CRU;
        end
      end
    end
    if (rst) begin
      last_reg <= 1'b1;  // 0 >= 0
      u_reg    <= 72'd0;
      v_reg    <= 47'd0;
      op_reg   <= OP_CRU;
      a_reg    <= 32'd0;
      vc_reg   <= 47'd0;
      vx_reg   <= 47'd0;
      vcma_reg <= 48'd0;
      vxpa_reg <= 48'd0;
      d_reg    <= 32'd0;
      n_reg    <= 24'd0;
    end
  end

  assign last = last_reg;
  assign op   = op_reg;
  assign v         = v_reg;
  assign vcruise_q = vc_reg;

endmodule

`default_nettype wire
