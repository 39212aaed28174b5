// segment_fifo: the command FIFO between frame_decoder and segment_prep, in block RAM (entry
// layout: docs/architecture.md "Command-FIFO entry"; `free` is the credit of docs/protocol.md
// "Device to host").
//
// Contract
//   s_axis_*   write side. s_axis_tready = (level < DEPTH), from registers only. An entry is
//              written on an edge with s_axis_tvalid and s_axis_tready high.
//   m_axis_*   read side, first-word-fall-through: m_axis_tvalid high while the output register
//              holds an entry (m_axis_tdata stable until the edge with m_axis_tready that takes
//              it). A stream kept ready is read at one entry per clock.
//   level      entries held (memory plus output register), 0..DEPTH; free = DEPTH - level.
//              Both registered; level rises on the write edge and falls on the take edge.
// Latency: write edge W -> m_axis_tvalid from edge W + 1 when the output register is free (the
//   memory holds the entry after W; the read issued in the next clock loads the output register
//   on edge W + 1).
// Memory: DEPTH x WIDTH, one write port, one registered read port with a read enable, no reset
//   and no read-during-write on the same address (a read is issued only for an entry written on
//   an earlier edge), so Quartus and Yosys map it to M10K blocks.
// DEPTH must be a power of two (pointers wrap), at most 32768.
//   flush      synchronous: empties the FIFO on this edge like rst (an entry offered on the same
//              edge is dropped); used by the e-stop.
// rst is synchronous, active high (empty; the memory contents are not cleared).
`default_nettype none

module segment_fifo #(
    parameter WIDTH = 350,  // the command-FIFO entry for 4 axes (segment_prep header)
    parameter DEPTH = 64
) (
    input wire clk,
    input wire rst,
    input wire flush,

    input  wire [WIDTH-1:0] s_axis_tdata,
    input  wire             s_axis_tvalid,
    output wire             s_axis_tready,

    output wire [WIDTH-1:0] m_axis_tdata,
    output wire             m_axis_tvalid,
    input  wire             m_axis_tready,

    output wire [15:0] level,
    output wire [15:0] free
);

  localparam AW = (DEPTH > 1) ? $clog2(DEPTH) : 1;
  localparam integer DEPTH_I = DEPTH;
  localparam [15:0] DEPTH16 = DEPTH_I[15:0];

  reg [WIDTH-1:0] mem[0:DEPTH-1];
  reg [WIDTH-1:0] rdata_reg;
  reg [AW-1:0] wr_ptr_reg, rd_ptr_reg;
  reg [15:0] mem_count_reg;  // entries in the memory, not yet read into the output register
  reg [15:0] level_reg;
  reg out_valid_reg;

  wire push = s_axis_tvalid && s_axis_tready;
  wire pop = out_valid_reg && m_axis_tready;
  wire rd_en = (mem_count_reg != 16'd0) && (!out_valid_reg || m_axis_tready);

  always @(posedge clk) begin
    if (push) mem[wr_ptr_reg] <= s_axis_tdata;
  end

  always @(posedge clk) begin
    if (rd_en) rdata_reg <= mem[rd_ptr_reg];
  end

  always @(posedge clk) begin
    if (push) wr_ptr_reg <= wr_ptr_reg + 1'b1;
    if (rd_en) rd_ptr_reg <= rd_ptr_reg + 1'b1;
    case ({push, rd_en})
      2'b10:   mem_count_reg <= mem_count_reg + 16'd1;
      2'b01:   mem_count_reg <= mem_count_reg - 16'd1;
      default: mem_count_reg <= mem_count_reg;
    endcase
    case ({push, pop})
      2'b10:   level_reg <= level_reg + 16'd1;
      2'b01:   level_reg <= level_reg - 16'd1;
      default: level_reg <= level_reg;
    endcase
    if (rd_en) out_valid_reg <= 1'b1;
    else if (pop) out_valid_reg <= 1'b0;
    if (rst || flush) begin
      wr_ptr_reg    <= {AW{1'b0}};
      rd_ptr_reg    <= {AW{1'b0}};
      mem_count_reg <= 16'd0;
      level_reg     <= 16'd0;
      out_valid_reg <= 1'b0;
    end
  end

  assign s_axis_tready = (level_reg < DEPTH16);
  assign m_axis_tdata  = rdata_reg;
  assign m_axis_tvalid = out_valid_reg;
  assign level         = level_reg;
  assign free          = DEPTH16 - level_reg;

`ifdef FORMAL
  // Formal properties (scripts/formal.sh, k-induction on a small DEPTH/WIDTH): never overflows or
  // underflows, the counters agree, and order with integrity: any one written entry, chosen by the
  // solver (f_pick), leaves as the (k+1)-th entry taken after its write, where k = the level at its
  // write, with exactly the data it was written with. Since the choice is arbitrary, every entry
  // leaves in its turn, unchanged (unless a flush empties the FIFO first: then it is empty on the
  // next clock).
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  (* anyseq *) reg f_pick;
  reg [1:0] f_state_reg;  // 0 nothing tracked, 1 tracked entry inside, 2 it has left
  reg [15:0] f_ahead_reg;  // entries in front of the tracked one
  reg [WIDTH-1:0] f_data_reg;
  wire [AW-1:0] f_addr = rd_ptr_reg + f_ahead_reg[AW-1:0] - {{(AW - 1) {1'b0}}, out_valid_reg};

  always @(posedge clk) begin
    if (f_state_reg == 2'd0 && push && f_pick) begin
      f_state_reg <= 2'd1;
      f_data_reg  <= s_axis_tdata;
      f_ahead_reg <= level_reg - {15'd0, pop};
    end else if (f_state_reg == 2'd1 && pop) begin
      if (f_ahead_reg == 16'd0) f_state_reg <= 2'd2;
      else f_ahead_reg <= f_ahead_reg - 16'd1;
    end
    if (rst || flush) begin  // a flush discards the tracked entry with all the others
      f_state_reg <= 2'd0;
      f_ahead_reg <= 16'd0;
    end
  end

  always @(*)
    if (f_past_valid && !rst) begin
      assert (level_reg <= DEPTH16);
      assert (mem_count_reg <= DEPTH16);
      assert (level_reg == mem_count_reg + {15'd0, out_valid_reg});
      assert ({{(16 - AW) {1'b0}}, wr_ptr_reg - rd_ptr_reg} == (mem_count_reg & (DEPTH16 - 16'd1)));
      assert (f_state_reg != 2'd3);
      if (f_state_reg == 2'd1) begin
        assert (f_ahead_reg < level_reg);
        // The tracked entry is taken now exactly when it is at the head: its data is intact.
        if (pop && f_ahead_reg == 16'd0) assert (m_axis_tdata == f_data_reg);
        // Induction invariant: where it is (output register, or memory behind rd_ptr).
        if (out_valid_reg && f_ahead_reg == 16'd0) assert (rdata_reg == f_data_reg);
        else assert (mem[f_addr] == f_data_reg);
      end
    end

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && $past(flush)) assert (level_reg == 16'd0 && !m_axis_tvalid);

  always @(posedge clk)
    if (f_past_valid && !$past(rst) && !$past(flush) && !rst) begin
      // A held output is not replaced before it is taken (unless flushed).
      if ($past(out_valid_reg) && !$past(m_axis_tready)) begin
        assert (out_valid_reg);
        assert (rdata_reg == $past(rdata_reg));
      end
      // No write into a full FIFO, no take from an empty one.
      if ($past(level_reg) == DEPTH16) assert (!$past(push));
      if ($past(level_reg) == 16'd0) assert (!$past(pop));
    end
`endif

endmodule

`default_nettype wire
