// The virtual board: cnc_core composed of its twins, driven by a host (v1 stop-and-wait or a v2
// streaming session, host_schedule.h) over the rx pin, answering on tx (docs/systemc.md).
//
//   host --pin--> UartRxTwin --bytes--> FrameDecoderTwin --fifo--> SegmentFifoTwin --out-->
//    ^                                   | resp  | cfg (board)                 SegmentPrepTwin
//    |                                   v                                        | segments
//    +--line-- UartTxTwin <--tx-- ResponseEncoderTwin <--done-- SegmentExecutorTwin
//                                   ^ state (board)          | dda[a]    | pulse[a]
//                                                            v           v
//                                                     DdaLinearTwin -> StepPulseTwin (x4)
//
// Jobs run in order in the host's thread (one SystemC elaboration can run many); each job
// starts at cycle 0 from the reset state with its own step timing.
//
// The motion rate (feed_rate.h) changes the clocks of the ticks of segments the executor twin
// has already computed (it computes each segment whole when it accepts it). So a job whose host
// sends MOTION frames runs again until it is consistent: a run with the requests of the MOTION
// frames known up front (their clocks and fields, from the previous run), whose MOTION frames
// are accepted exactly there, is the job's run. A run stops at the first MOTION frame it did not
// know: the effect of a request starts two edges after its frame ends, so everything before was
// exact and the next run knows that request too (a job with n MOTION frames without CANCEL runs
// n + 1 times, all but the last cut short at a MOTION frame). A CANCEL's flush (the first clock
// with cancel and r = 0: the rate's hold and cancel clear, the FIFO, the prep and the executor
// drop what they hold on the next edge) is settled the same way: a run knows the flush clocks
// the run before found (known_flush_), stops once its host's time passes a CANCEL whose flush it
// does not know, and the job runs again until the flushes it knows are the ones it finds
// (settle_motion). A live session (TwinBoard) does the same from its own log: at a MOTION frame
// it did not know it runs again from the reset with every host byte so far at its clock and the
// requests known up front (twin_board.h).
//
// The host sends each packet with its delay; the response encoder computes the answers lazily,
// in time order, up to the edge before which every input is known (docs/systemc.md "Time").
#pragma once

#include <functional>
#include <memory>

#include <deque>

#include "fpgacnc/twins/frame_decoder.h"
#include "fpgacnc/twins/host_schedule.h"
#include "fpgacnc/twins/input_filter.h"
#include "fpgacnc/twins/response_encoder.h"
#include "fpgacnc/twins/run_result.h"
#include "fpgacnc/twins/segment_executor.h"
#include "fpgacnc/twins/segment_fifo.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/uart_rx.h"
#include "fpgacnc/twins/uart_tx.h"

// After <systemc> (tlm_common.h): the header uses sc_core without including it.
#include <tlm_utils/tlm_quantumkeeper.h>

namespace fpgacnc::twins {

struct TwinJob {
  HostScript script;
  std::array<AxisTiming, kAxes> timing{};
  std::function<void(RunResult&&)> done;  // called in the host thread at the job's end
};

class TwinBoard;

// Sorts edges by (cycle, signal, value) and drops the laser fall/rise pairs on one edge of
// back-to-back cutting segments (the pin stays high), as the RTL recorder sees them.
void sort_edges(std::vector<Edge>& edges);

class VirtualBoard : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(VirtualBoard);
  // `p`: clock, baud, watchdog, defaults (the timing of each job replaces p.timing).
  VirtualBoard(sc_core::sc_module_name name, const CoreParams& p, bool record_tx = false);
  void add_job(TwinJob job) { jobs_.push_back(std::move(job)); }
  // sc_time quantum of the host's quantum keeper (default 1 ms).
  void set_quantum(const sc_core::sc_time& q) { quantum_ = q; }
  const CoreParams& params() const { return p_; }
  // Machine outputs (OUTPUT frames) as pin edges: coolant, fan PWM, digital outputs (off: the
  // edge list has STEP/DIR/LASER/TX only, as the Verilated board records it).
  void record_outputs(bool on) { exec_.record_outputs = on; }
  // A job's RunResult without its edge list: the net steps and the edge count only
  // (PinRecorder::summary_only; for whole files of hundreds of millions of edges).
  void summary_only(bool on) { pins_.summary_only = on; }
  // Runs of the last job (1 without MOTION frames; see above).
  int runs() const { return runs_; }
  // Called in the host thread after the jobs: a TwinBoard's pty sessions (twin_board.h).
  std::function<void(VirtualBoard&)> live;

 private:
  friend class TwinBoard;
  void host_thread();
  void on_line(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay);
  void on_cfg(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay);
  void on_state(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay);
  void reset(const std::array<AxisTiming, kAxes>& timing);
  RunResult run_job(const TwinJob& job);
  RunResult run_once(const TwinJob& job, bool sync);  // sync: let SystemC time pass
  // Gives the host the tx bytes whose stop-bit centre is before edge `before` (all when
  // `one` is false; only the next one otherwise). Returns the number given.
  size_t deliver(Cycle before, bool one);

  CoreParams p_;
  CycleClock clk_;
  PinRecorder pins_;
  UartRxTwin rx_;
  FrameDecoderTwin dec_;
  SegmentFifoTwin fifo_;
  SegmentPrepTwin prep_;
  SegmentExecutorTwin exec_;
  FeedRate rate_;
  std::vector<MotionReq> known_motion_;  // requests known up front (a job's later runs)
  // Per known request: the flush clock of a CANCEL (the first clock with cancel and r = 0),
  // kFlushNone (not a CANCEL, or one within a cancel in progress), kFlushUnknown.
  static constexpr Cycle kFlushNone = -1, kFlushUnknown = -2;
  std::vector<Cycle> known_flush_;
  std::vector<Cycle> flush_edges_;  // their abort edges (flush clock + 1), in order
  // The flushes as this run's rate has them (for the requests known up front).
  std::vector<Cycle> observe_flushes();
  // After a run (or a replay): true when the requests and flushes known up front are this run's;
  // otherwise they are updated for the next run.
  bool settle_motion();
  // A CANCEL with its flush unknown whose effect has begun by clock t: everything that can come
  // before its flush is known, so the run stops and the next one knows it.
  bool flush_unknown_before(Cycle t) const;
  std::vector<MotionReq> observed_motion_;  // MOTION frames accepted in this run
  bool motion_mismatch_ = false;            // a MOTION frame accepted that was not known
  int runs_ = 0;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda_;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse_;
  ResponseEncoderTwin enc_;
  UartTxTwin tx_;
  tlm_utils::simple_initiator_socket<VirtualBoard> host_pin_;
  tlm_utils::simple_target_socket<VirtualBoard> host_line_;
  tlm_utils::simple_target_socket<VirtualBoard> cfg_;
  tlm_utils::simple_target_socket<VirtualBoard> state_;
  // The executor's abort input (AbortSpan). Not driven yet: the board has no e-stop input.
  tlm_utils::simple_initiator_socket<VirtualBoard> abort_;
  tlm::tlm_generic_payload gp_;
  std::vector<TwinJob> jobs_;
  Host* host_ = nullptr;
  std::deque<std::pair<Cycle, uint8_t>> tx_bytes_;  // (start edge, byte) not yet given
  std::vector<Cycle> entry_ends_;                   // per FIFO entry: busy until after this edge
  std::vector<std::pair<Cycle, CfgAxis>> pending_cfg_;  // CONFIG_AXIS in the shadow registers
  void apply_cfg(Cycle write);
  int64_t tx_centre9_ = 0;  // start -> stop-bit centre
  sc_core::sc_time quantum_{1, sc_core::SC_MS};
};

// Runs one job on a fresh virtual board: elaborates, sc_start()s and returns. SystemC allows
// one elaboration per process, so call this at most once (the CLI does).
RunResult run_on_twins(const CoreParams& p, HostScript script, bool record_tx = false);

}  // namespace fpgacnc::twins
