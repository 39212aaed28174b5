// The virtual board: cnc_core composed of its twins, driven by the stop-and-wait host over
// the rx pin, answering on tx (docs/systemc.md).
//
//   VirtualHost --pin--> UartRxTwin --bytes--> PacketDecoderTwin --commands--> SegmentPrepTwin
//        ^                                                                       | segments
//        |                                                                       v
//        +--line-- UartTxTwin <--tx-- StatusAckTwin <--done-- SegmentExecutorTwin
//                                                              | dda[a]    | pulse[a]
//                                                              v           v
//                                                       DdaLinearTwin -> StepPulseTwin (x4)
//
// Jobs run in order in the host's thread (one SystemC elaboration can run many); each job
// starts at cycle 0 from the reset state with its own step timing.
#pragma once

#include <functional>
#include <memory>

#include "fpgacnc/twins/host_schedule.h"
#include "fpgacnc/twins/packet_decoder_v1.h"
#include "fpgacnc/twins/run_result.h"
#include "fpgacnc/twins/segment_executor.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/status_ack.h"
#include "fpgacnc/twins/uart_rx.h"
#include "fpgacnc/twins/uart_tx.h"

// After <systemc> (tlm_common.h): the header uses sc_core without including it.
#include <tlm_utils/tlm_quantumkeeper.h>

namespace fpgacnc::twins {

struct TwinJob {
  std::vector<HostPacket> packets;
  std::array<AxisTiming, kAxes> timing{};
  std::function<void(RunResult&&)> done;  // called in the host thread at the job's end
};

class VirtualBoard : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(VirtualBoard);
  // `p`: clock, baud, watchdog, defaults (the timing of each job replaces p.timing).
  VirtualBoard(sc_core::sc_module_name name, const CoreParams& p, bool record_tx = false);
  void add_job(TwinJob job) { jobs_.push_back(std::move(job)); }
  // sc_time quantum of the host's quantum keeper (default 1 ms).
  void set_quantum(const sc_core::sc_time& q) { quantum_ = q; }
  const CoreParams& params() const { return p_; }

 private:
  void host_thread();
  void on_line(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay);
  void reset(const std::array<AxisTiming, kAxes>& timing);
  RunResult run_job(const TwinJob& job);

  CoreParams p_;
  CycleClock clk_;
  PinRecorder pins_;
  UartRxTwin rx_;
  PacketDecoderTwin dec_;
  SegmentPrepTwin prep_;
  SegmentExecutorTwin exec_;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda_;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse_;
  StatusAckTwin status_;
  UartTxTwin tx_;
  tlm_utils::simple_initiator_socket<VirtualBoard> host_pin_;
  tlm_utils::simple_target_socket<VirtualBoard> host_line_;
  tlm::tlm_generic_payload gp_;
  std::vector<TwinJob> jobs_;
  StopAndWaitHost* host_ = nullptr;
  sc_core::sc_time quantum_{1, sc_core::SC_MS};
};

// Runs one job on a fresh virtual board: elaborates, sc_start()s and returns. SystemC allows
// one elaboration per process, so call this at most once (the CLI does).
RunResult run_on_twins(const CoreParams& p, std::vector<HostPacket> packets,
                       bool record_tx = false);

}  // namespace fpgacnc::twins
