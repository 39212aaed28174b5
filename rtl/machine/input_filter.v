// input_filter: conditions N asynchronous machine inputs (switches, buttons): per input a two-flop
// synchronizer, a polarity, a debounce counter and an edge strobe (docs/machine.md "Inputs").
//
// Contract
//   din[i]       asynchronous pin level.
//   ACTIVE_LOW   bit i = 1: input i is asserted when its pin is low (inverted after the
//                synchronizer); 0: asserted when high.
//   FILTER_CLKS  debounce length F (0 .. 2^24 - 1). The synchronized, polarity-corrected sample of
//                input i must differ from q[i] on F consecutive clocks; on the edge after the F-th
//                q[i] takes it. Any clock on which the sample equals q[i] restarts the count, so
//                a bounce shorter than F clocks never reaches q. F = 0 acts as 1: the
//                synchronizer and one register only.
//   q[i]         filtered level, 1 = asserted. A pin level that first reaches s1 on edge p
//                (and then stays) changes q on edge p + 1 + max(F, 1).
//   strobe[i]    1-clock strobe, high exactly in the first clock q[i] has its new value.
//   rst          synchronous, active high: q = 0 (not asserted), counters 0. Sync flops reset to
//                the not-asserted level too, so an input held asserted through reset is seen
//                as a change after the filter length.
// Resources: per input two sync flops, q, edge and one counter of CW bits (no division).
// Parameters are checked at elaboration: a wrong value instantiates a module named
// input_filter_illegal_<rule>, which does not exist.
`default_nettype none

module input_filter #(
    parameter             N           = 4,
    parameter             FILTER_CLKS = 16,
    parameter [N-1:0]     ACTIVE_LOW  = {N{1'b0}}
) (
    input  wire         clk,
    input  wire         rst,
    input  wire [N-1:0] din,
    output wire [N-1:0] q,
    output wire [N-1:0] strobe
);

  localparam integer F = (FILTER_CLKS < 1) ? 1 : FILTER_CLKS;
  localparam integer CW = (F < 2) ? 1 : $clog2(F);
  localparam integer FM1_I = F - 1;
  localparam [CW-1:0] FM1 = FM1_I[CW-1:0];

  generate
    if (N < 1 || N > 32) begin : g_bad_n
      input_filter_illegal_N_not_1_to_32 u_err ();
    end
    if (FILTER_CLKS < 0 || FILTER_CLKS > 16777215) begin : g_bad_filter
      input_filter_illegal_FILTER_CLKS_not_0_to_2p24m1 u_err ();
    end
  endgenerate

  reg [N-1:0] s1_reg, s2_reg, q_reg, edge_reg;
  reg [CW*N-1:0] cnt_reg;

  wire [N-1:0] sample = s2_reg ^ ACTIVE_LOW;  // 1 = asserted

  integer i;
  always @(posedge clk) begin
    s1_reg <= din;
    s2_reg <= s1_reg;
    for (i = 0; i < N; i = i + 1) begin
      edge_reg[i] <= 1'b0;
      if (sample[i] == q_reg[i]) begin
        cnt_reg[CW*i+:CW] <= {CW{1'b0}};
      end else if (cnt_reg[CW*i+:CW] == FM1) begin
        cnt_reg[CW*i+:CW] <= {CW{1'b0}};
        q_reg[i]          <= sample[i];
        edge_reg[i]       <= 1'b1;
      end else begin
        cnt_reg[CW*i+:CW] <= cnt_reg[CW*i+:CW] + 1'b1;
      end
    end
    if (rst) begin
      s1_reg   <= ACTIVE_LOW;
      s2_reg   <= ACTIVE_LOW;
      q_reg    <= {N{1'b0}};
      edge_reg <= {N{1'b0}};
      cnt_reg  <= {CW * N{1'b0}};
    end
  end

  assign q      = q_reg;
  assign strobe = edge_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh set input_filter: k-induction, and cover traces). Reset
  // in the first clock; din is free. A monitor per input counts the consecutive clocks the
  // synchronized sample has differed from q (saturating above F).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  localparam integer FW = CW + 1;
  localparam integer F_I = F;
  localparam [FW-1:0] FF = F_I[FW-1:0];
  reg [FW*N-1:0] f_diff;  // consecutive differing samples seen before this clock
  reg [N-1:0] f_bounced;  // a difference was rejected (the sample returned before F)
  integer k;
  always @(posedge clk) begin
    for (k = 0; k < N; k = k + 1) begin
      if (sample[k] == q_reg[k]) begin
        if (f_diff[FW*k+:FW] != {FW{1'b0}}) f_bounced[k] <= 1'b1;
        f_diff[FW*k+:FW] <= {FW{1'b0}};
      end else if (f_diff[FW*k+:FW] == FF - 1'b1) begin
        f_diff[FW*k+:FW] <= {FW{1'b0}};
      end else begin
        f_diff[FW*k+:FW] <= f_diff[FW*k+:FW] + 1'b1;
      end
    end
    if (rst) begin
      f_diff    <= {FW * N{1'b0}};
      f_bounced <= {N{1'b0}};
    end
  end

  genvar g;
  generate
    for (g = 0; g < N; g = g + 1) begin : g_f
      always @(*)
        if (f_past_valid) begin
          // Invariant: the counter is the monitor's count of differing samples.
          assert ({1'b0, cnt_reg[CW*g+:CW]} == f_diff[FW*g+:FW]);
          assert (f_diff[FW*g+:FW] < FF);
        end
      always @(posedge clk)
        if (f_past_valid && !$past(rst)) begin
          // q changes only after F consecutive synchronized samples at the new level.
          if (q_reg[g] != $past(q_reg[g])) begin
            assert ($past(f_diff[FW*g+:FW]) == FF - 1'b1);
            assert ($past(sample[g]) == q_reg[g]);
          end
          // The strobe is high exactly in the first clock of a new q.
          assert (edge_reg[g] == (q_reg[g] != $past(q_reg[g])));
        end
      // Covers: a filtered change (q rises), and a rejected bounce (the sample left q and came
      // back before F clocks) followed by a filtered change.
      always @(posedge clk)
        if (f_past_valid && !rst) begin
          cover (edge_reg[g] && q_reg[g]);
          cover (f_bounced[g] && edge_reg[g] && q_reg[g]);
        end
    end
  endgenerate
`endif

endmodule

`default_nettype wire
