// pid_incr: one heater channel's controller (docs/heater.md "Control law"), fixed point.
//
// Contract
//   start       1-clock strobe: compute u(k) from temp and setpoint (sampled on this edge with all
//               the settings; they must stay stable until done). Ignored while busy.
//   enable      low: u = 0 and the next enabled sample is a first sample (restart).
//   restart     1-clock strobe (mode changed): the next sample is a first sample, u(k-1) = 0.
//   mode        0 OFF, 1 MANUAL, 2 ON_OFF, 3 P, 4 PID (5..7 act as OFF).
//   temp, setpoint  Q11.4 degC (s16). e = setpoint - temp, s17.
//   kp, ki, kd  Q8.24 duty per degC (u32). umax, manual: Q1.15 (u16, <= 0x8000). hyst: Q12.4 (u16).
//   u           Q1.28 (u29) output, 0 .. umax << 13, registered, changes on the done edge.
//   done        1-clock strobe: u holds u(k).
// Law (PID): u(k) = clamp(u(k-1) + kp*(e - e1) + [integrate] ki*e + kd*(e - 2 e1 + e2), 0, umax)
//   with integrate = !((u(k-1) >= umax && e > 0) || (u(k-1) == 0 && e < 0)); first sample:
//   e1 = e2 = e, u(k-1) = 0. P: clamp(kp*e, 0, umax). ON_OFF: e > hyst -> umax, e < -hyst -> 0,
//   else u(k-1) (0 on a first sample). MANUAL: min(manual, umax). Every product is exact (Q.28),
//   sums are 56-bit: u(k) equals the double-precision law
//   (models/include/fpgacnc/models/pid_ref.h) with the same coefficients exactly.
// Multiplies: one sequential shift-add multiplier (32 x 20 bits, one bit per clock): no DSP
// block, no `*`, no `/`. Latency: start at edge S -> done high after edge S + 3 + 22 * products:
//   PID 69 clocks (3 products; 47 without the integral), P 25, other modes 2 (the bench measures
//   at most 68 from the clock after start).
// rst is synchronous, active high (u = 0, first sample pending).
`default_nettype none

module pid_incr (
    input wire clk,
    input wire rst,

    input wire               start,
    input wire               enable,
    input wire               restart,
    input wire        [ 2:0] mode,
    input wire signed [15:0] temp,
    input wire signed [15:0] setpoint,
    input wire        [31:0] kp,
    input wire        [31:0] ki,
    input wire        [31:0] kd,
    input wire        [15:0] umax,
    input wire        [15:0] hyst,
    input wire        [15:0] manual,

    output wire [28:0] u,
    output wire        done,
    output wire        busy
);

  localparam [2:0] M_OFF = 3'd0, M_MANUAL = 3'd1, M_ONOFF = 3'd2, M_P = 3'd3, M_PID = 3'd4;
  localparam [2:0] S_IDLE = 3'd0, S_ERR = 3'd1, S_LOAD = 3'd2, S_MUL = 3'd3, S_ADD = 3'd4,
                   S_CLAMP = 3'd5;

  reg [2:0] st_reg;
  reg fresh_reg;
  reg [28:0] u_reg;
  reg done_reg;
  reg signed [19:0] e_reg, e1_reg, e2_reg;  // s17 values held in 20 bits
  reg signed [55:0] sum_reg;
  reg [1:0] term_reg;  // product being computed: 0 kp*(e-e1) (P: kp*e), 1 kd*d2, 2 ki*e
  reg last_term_reg;  // the current product is the last one
  reg integrate_reg;
  // shift-add multiplier
  reg [51:0] mcand_reg;  // coefficient, shifted left one bit per clock
  reg [19:0] mplier_reg;  // magnitude of the multiplier, shifted right
  reg mneg_reg;
  reg [51:0] macc_reg;
  reg [4:0] mcnt_reg;

  // The operands and sums below are block-local regs formed in the state that uses them: the
  // same logic as continuous assignments, and a simulator evaluates them only in that state.
  always @(posedge clk) begin : seq
    reg [28:0] umax28, man28;
    reg signed [19:0] hyst20, d1, d2, op_val;
    reg [31:0] op_coef;
    reg signed [55:0] prod;
    done_reg <= 1'b0;
    case (st_reg)
      S_IDLE:
      if (start) begin
        e_reg  <= {{4{setpoint[15]}}, setpoint} - {{4{temp[15]}}, temp};
        st_reg <= S_ERR;
      end
      S_ERR: begin
        // e_reg holds e(k). Decide by mode.
        umax28 = {umax[15:0], 13'd0};
        man28  = (manual > umax) ? umax28 : {manual[15:0], 13'd0};
        hyst20 = {4'd0, hyst};
        if (!enable || mode > M_PID || mode == M_OFF) begin
          u_reg     <= 29'd0;
          fresh_reg <= 1'b1;
          done_reg  <= 1'b1;
          st_reg    <= S_IDLE;
        end else if (mode == M_MANUAL) begin
          u_reg     <= man28;
          fresh_reg <= 1'b0;
          done_reg  <= 1'b1;
          st_reg    <= S_IDLE;
        end else if (mode == M_ONOFF) begin
          if (e_reg > hyst20) u_reg <= umax28;
          else if (e_reg < -hyst20) u_reg <= 29'd0;
          else if (fresh_reg) u_reg <= 29'd0;
          fresh_reg <= 1'b0;
          done_reg  <= 1'b1;
          st_reg    <= S_IDLE;
        end else if (mode == M_P) begin
          sum_reg       <= 56'sd0;
          term_reg      <= 2'd0;
          last_term_reg <= 1'b1;
          st_reg        <= S_LOAD;
        end else begin  // PID
          if (fresh_reg) begin
            e1_reg <= e_reg;
            e2_reg <= e_reg;
          end
          sum_reg <= fresh_reg ? 56'sd0 : {27'd0, u_reg};
          integrate_reg <= !(((fresh_reg ? 29'd0 : u_reg) >= umax28 && e_reg > 20'sd0) ||
                             ((fresh_reg || u_reg == 29'd0) && e_reg < 20'sd0));
          term_reg <= 2'd0;
          last_term_reg <= 1'b0;
          st_reg <= S_LOAD;
        end
      end
      S_LOAD: begin
        // operand of the next product
        d1 = e_reg - e1_reg;
        d2 = e_reg - (e1_reg <<< 1) + e2_reg;
        case (term_reg)
          2'd0: begin
            op_coef = kp;
            op_val  = (mode == M_P) ? e_reg : d1;
          end
          2'd1: begin
            op_coef = kd;
            op_val  = d2;
          end
          default: begin
            op_coef = ki;
            op_val  = e_reg;
          end
        endcase
        mcand_reg  <= {20'd0, op_coef};
        mplier_reg <= op_val[19] ? -op_val : op_val;
        mneg_reg   <= op_val[19];
        macc_reg   <= 52'd0;
        mcnt_reg   <= 5'd0;
        st_reg     <= S_MUL;
      end
      S_MUL: begin
        if (mplier_reg[0]) macc_reg <= macc_reg + mcand_reg;
        mcand_reg  <= mcand_reg << 1;
        mplier_reg <= mplier_reg >> 1;
        mcnt_reg   <= mcnt_reg + 5'd1;
        if (mcnt_reg == 5'd19) st_reg <= S_ADD;
      end
      S_ADD: begin
        prod = mneg_reg ? -$signed({4'd0, macc_reg}) : $signed({4'd0, macc_reg});
        sum_reg <= sum_reg + prod;
        if (last_term_reg) begin
          st_reg <= S_CLAMP;
        end else begin
          // next term: kd*d2, then ki*e when integrating
          term_reg      <= term_reg + 2'd1;
          last_term_reg <= (term_reg == 2'd1) || (term_reg == 2'd0 && !integrate_reg);
          st_reg        <= S_LOAD;
        end
      end
      default: begin  // S_CLAMP
        umax28 = {umax[15:0], 13'd0};
        if (sum_reg < 56'sd0) u_reg <= 29'd0;
        else if (sum_reg > $signed({27'd0, umax28})) u_reg <= umax28;
        else u_reg <= sum_reg[28:0];
        if (mode == M_PID) begin
          e2_reg <= e1_reg;
          e1_reg <= e_reg;
        end
        fresh_reg <= 1'b0;
        done_reg  <= 1'b1;
        st_reg    <= S_IDLE;
      end
    endcase
    if (restart) fresh_reg <= 1'b1;  // wins over a sample that completes on the same edge
    if (rst) begin
      st_reg        <= S_IDLE;
      fresh_reg     <= 1'b1;
      u_reg         <= 29'd0;
      done_reg      <= 1'b0;
      e_reg         <= 20'sd0;
      e1_reg        <= 20'sd0;
      e2_reg        <= 20'sd0;
      sum_reg       <= 56'sd0;
      term_reg      <= 2'd0;
      last_term_reg <= 1'b0;
      integrate_reg <= 1'b0;
      mcand_reg     <= 52'd0;
      mplier_reg    <= 20'd0;
      mneg_reg      <= 1'b0;
      macc_reg      <= 52'd0;
      mcnt_reg      <= 5'd0;
    end
  end

  assign u    = u_reg;
  assign done = done_reg;
  assign busy = (st_reg != S_IDLE);

endmodule

`default_nettype wire
