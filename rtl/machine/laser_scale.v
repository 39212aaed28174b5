// laser_scale: the laser / spindle PWM's duty from the segment's power byte, serially: M3 (dyn 0)
// the power itself, M4 (dyn 1) the power times the actual speed over the programmed one
// (docs/machine.md "Laser and spindle PWM").
//
// Contract
//   start     1-clock strobe: the inputs of this clock are taken (a start while busy restarts).
//   power     the running segment's power byte (0 .. 255).
//   dyn       M4 dynamic power: the rate and the profile ratio apply.
//   prof      the running segment is a LINE_PROFILE (its V / V_cruise applies, with dyn).
//   rate      feed_rate's rate r, 0 .. 2^32 (2^32 = 100 %).
//   v, vc     profile_gen's V and V_cruise (V <= V_cruise, V_cruise >= 1: the decoder's rules).
//   duty      registered, valid from the clock LAT clocks after the start clock (done high in
//             it) until the next result: dyn 0: power; dyn 1:
//               duty = floor(power * q_r * q_v / 2^32), q_r = floor(r / 2^16) (0 .. 65 536),
//               q_v = floor(2^16 * V / V_cruise) with prof, else 2^16,
//             so at 100 % and cruise duty = power, and duty is floor(power * ratio) or one count
//             less (q_r and q_v each lose less than 2^-16 of the ratio: power * 2^-15 < 1 count).
//   done      1-clock strobe in the first clock duty holds the new result.
// Work: 17 clocks of a restoring division (V / V_cruise, one quotient bit a clock), 17 of a
// shift-and-add multiply (q_r * q_v), 8 of another (power * that): LAT = 1 + 17 + 17 + 8 = 43
// clocks (`FPGACNC_DEF_LASER_SCALE_CLKS, which laser_pwm is given too). No `/`, `%` or `*`. A
// LAT other than that instantiates laser_scale_illegal_LAT_mismatch, which does not exist.
// rst is synchronous, active high (idle, duty 0).
`default_nettype none
`include "fpgacnc_spec.vh"

module laser_scale #(
    parameter LAT = `FPGACNC_DEF_LASER_SCALE_CLKS
) (
    input wire clk,
    input wire rst,

    input wire        start,
    input wire [ 7:0] power,
    input wire        dyn,
    input wire        prof,
    input wire [32:0] rate,
    input wire [46:0] v,
    input wire [46:0] vc,

    output wire [7:0] duty,
    output wire       done
);

  localparam integer QBITS = 17;  // q_v and q_r: 0 .. 2^16
  localparam integer PBITS = 8;  // the power byte
  localparam integer LAT_OWN = 1 + QBITS + QBITS + PBITS;
  localparam integer Q_LAST_I = QBITS - 1;
  localparam integer P_LAST_I = PBITS - 1;
  localparam [4:0] Q_LAST = Q_LAST_I[4:0];
  localparam [4:0] P_LAST = P_LAST_I[4:0];

  generate
    if (LAT != LAT_OWN) begin : g_bad_lat
      laser_scale_illegal_LAT_mismatch u_err ();
    end
  endgenerate

  localparam [1:0] P_IDLE = 2'd0, P_DIV = 2'd1, P_MUL1 = 2'd2, P_MUL2 = 2'd3;

  reg [ 1:0] phase_reg;
  reg [ 4:0] k_reg;  // iterations left in the phase, minus 1
  reg [47:0] acc_reg;  // DIV: the remainder (< 2 V_cruise); MUL1, MUL2: the product
  reg [46:0] opnd_reg;  // DIV: V_cruise; MUL2: q_r * q_v (34 bits)
  reg [16:0] q_reg;  // DIV: q_v, bit by bit; MUL1: the multiplicand q_v
  reg [16:0] qr_reg;  // MUL1: q_r, consumed from its top bit
  reg [ 7:0] p_reg;  // MUL2: the power, consumed from its top bit
  reg        div_reg;  // the division's quotient is used (dyn and prof), else q_v = 2^16
  reg [ 7:0] duty_reg;
  reg        done_reg;

  // DIV: rem - V_cruise; its borrow is the quotient bit (then the difference is < 2^47)
  /* verilator lint_off UNUSEDSIGNAL */
  wire [48:0] diff = {1'b0, acc_reg} - {2'b00, opnd_reg};  // [47]: 0 whenever ge
  /* verilator lint_on UNUSEDSIGNAL */
  wire        ge = !diff[48];
  // MUL1, MUL2 (one adder): acc = 2 acc + the multiplicand where the multiplier's top bit is set
  wire [47:0] addend = (phase_reg == P_MUL1) ? (qr_reg[16] ? {31'd0, q_reg} : 48'd0) :
                                               (p_reg[7] ? {1'b0, opnd_reg} : 48'd0);
  wire [47:0] mul_next = {acc_reg[46:0], 1'b0} + addend;

  always @(posedge clk) begin
    done_reg <= 1'b0;
    case (phase_reg)
      P_DIV: begin
        // rem < 2 V_cruise: one quotient bit, then rem = 2 (rem - bit * V_cruise)
        if (div_reg) q_reg <= {q_reg[15:0], ge};
        acc_reg <= {(ge ? diff[46:0] : acc_reg[46:0]), 1'b0};
        k_reg   <= k_reg - 5'd1;
        if (k_reg == 5'd0) begin
          phase_reg <= P_MUL1;
          k_reg     <= Q_LAST;
          acc_reg   <= 48'd0;
        end
      end
      P_MUL1: begin
        acc_reg <= mul_next;
        qr_reg  <= {qr_reg[15:0], 1'b0};
        k_reg   <= k_reg - 5'd1;
        if (k_reg == 5'd0) begin
          phase_reg <= P_MUL2;
          k_reg     <= P_LAST;
          opnd_reg  <= mul_next[46:0];
          acc_reg   <= 48'd0;
        end
      end
      P_MUL2: begin
        acc_reg <= mul_next;
        p_reg   <= {p_reg[6:0], 1'b0};
        k_reg   <= k_reg - 5'd1;
        if (k_reg == 5'd0) begin
          phase_reg <= P_IDLE;
          done_reg  <= 1'b1;
          duty_reg  <= mul_next[39:32];  // dyn 0: q_r = q_v = 2^16, the power
        end
      end
      default: ;
    endcase
    if (start) begin
      phase_reg <= P_DIV;
      k_reg     <= Q_LAST;
      acc_reg   <= {1'b0, v};
      opnd_reg  <= vc;
      q_reg     <= 17'h10000;  // 2^16 unless the division replaces it
      qr_reg    <= dyn ? rate[32:16] : 17'h10000;
      p_reg     <= power;
      div_reg   <= dyn && prof;
    end
    if (rst) begin
      phase_reg <= P_IDLE;
      k_reg     <= 5'd0;
      acc_reg   <= 48'd0;
      opnd_reg  <= 47'd0;
      q_reg     <= 17'd0;
      qr_reg    <= 17'd0;
      p_reg     <= 8'd0;
      div_reg   <= 1'b0;
      duty_reg  <= 8'd0;
      done_reg  <= 1'b0;
    end
  end

  assign duty = duty_reg;
  assign done = done_reg;

  /* verilator lint_off UNUSEDSIGNAL */
  wire unused_rate = &{1'b0, rate[15:0]};
  /* verilator lint_on UNUSEDSIGNAL */

endmodule

`default_nettype wire
