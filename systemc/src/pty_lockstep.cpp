#include "fpgacnc/twins/pty_lockstep.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "fpgacnc/link/serial_link.h"

namespace fpgacnc::twins {
namespace {

using wall_clock = std::chrono::steady_clock;

std::string describe(const models::Edge& e) {
  return fmt::format("cycle {} {} -> {}", e.cycle, models::signal_name(e.signal), e.value);
}

}  // namespace

LockstepRun run_lockstep(simboard::Board& board, const HostScript& script, uint64_t clk_hz,
                         uint32_t baud, std::chrono::milliseconds timeout) {
  LockstepRun r;
  r.model = board.model();
  const auto t0 = wall_clock::now();
  board.start();
  link::SerialLink lk(board.path(), baud);
  const SenderTiming sender{clk_hz, baud};
  auto host = make_host(script, sender, sender.frame());
  std::vector<uint8_t> batch;
  uint64_t written = 0;
  auto exchange = [&]() -> bool {
    if (!batch.empty()) {
      lk.write(batch);
      written += batch.size();
      batch.clear();
      ++r.batches;
    }
    const auto deadline = wall_clock::now() + timeout;
    // Polls back off to 1 ms: a SimBoard yields its clock loop to every reader. Answers are read
    // as they come (a board may wait for its client to read them) and given to the host only
    // once the board is idle. bytes_in first: a board counts bytes only after it has taken them.
    auto pause = std::chrono::microseconds(50);
    std::vector<uint8_t> got;
    for (;;) {
      while (const auto b = lk.read_byte(std::chrono::milliseconds(0))) got.push_back(*b);
      if (board.stats().bytes_in >= written && board.idle_for_host()) break;
      if (wall_clock::now() >= deadline) {
        r.error = fmt::format("{} board not idle {} ms after batch {} ({} bytes written)", r.model,
                              timeout.count(), r.batches, written);
        return false;
      }
      std::this_thread::sleep_for(pause);
      pause = std::min<std::chrono::microseconds>(pause * 2, std::chrono::milliseconds(1));
    }
    const uint64_t out = board.stats().bytes_out;
    while (r.received.size() + got.size() < out) {
      const auto b = lk.read_byte(std::chrono::milliseconds(2000));
      if (!b) {
        r.error = fmt::format("{} board: answer byte {} of {} not readable from {}", r.model,
                              r.received.size() + got.size(), out, board.path());
        return false;
      }
      got.push_back(*b);
    }
    for (uint8_t b : got) {
      r.received.push_back(b);
      host->on_tx_byte(0, b);
    }
    if (host->waiting() && got.empty()) {
      const auto st = board.stats();
      r.error = fmt::format(
          "{} board: no answer after packet {} (batch {}; board at cycle {}: {} bytes read, {} "
          "answered, {} moves done)",
          r.model, host->packets_sent(), r.batches, st.cycles, st.bytes_in, st.bytes_out,
          st.moves_done);
      return false;
    }
    return true;
  };
  while (!host->done()) {
    const auto frames = host->next_packet();
    if (!frames.empty()) {
      for (const HostFrame& f : frames) batch.push_back(f.byte);
      continue;
    }
    if (host->done()) break;
    if (!exchange()) break;
  }
  if (r.error.empty()) exchange();  // the last batch and its answers (a v1 job's last ACK)
  board.wait_quiet(std::chrono::milliseconds(2000));
  board.stop();
  r.packets = host->packets_sent();
  r.stats = board.stats();
  r.edges = board.edges();
  r.wall_s = std::chrono::duration<double>(wall_clock::now() - t0).count();
  return r;
}

std::vector<std::pair<uint64_t, uint8_t>> tx_bytes_from_edges(
    const std::vector<models::Edge>& edges, double clk_hz, double baud) {
  // The TX level after each edge; a byte starts on a fall while idle and is sampled at the bit
  // centres (as the board's UART monitor samples it).
  std::vector<std::pair<uint64_t, int>> tx;
  for (const auto& e : edges)
    if (e.signal == models::kTx) tx.emplace_back(e.cycle, e.value);
  const double cpb = clk_hz / baud;
  std::vector<std::pair<uint64_t, uint8_t>> out;
  size_t i = 0;
  auto level_at = [&](uint64_t c) {
    int lv = 1;
    for (size_t k = i; k < tx.size() && tx[k].first <= c; ++k) lv = tx[k].second;
    return lv;
  };
  while (i < tx.size()) {
    if (tx[i].second != 0) {
      ++i;
      continue;
    }
    const uint64_t start = tx[i].first;
    uint8_t v = 0;
    for (int b = 1; b <= 8; ++b) {
      const auto c = start + static_cast<uint64_t>(std::ceil((b + 0.5) * cpb));
      v |= static_cast<uint8_t>(level_at(c) << (b - 1));
    }
    out.emplace_back(start, v);
    const auto stop = start + static_cast<uint64_t>(std::ceil(9.5 * cpb));
    while (i < tx.size() && tx[i].first <= stop) ++i;
  }
  return out;
}

std::string compare_lockstep(const LockstepRun& a, const LockstepRun& b, double clk_hz,
                             double baud) {
  if (!a.error.empty()) return a.error;
  if (!b.error.empty()) return b.error;
  const auto ta = tx_bytes_from_edges(a.edges, clk_hz, baud);
  const auto tb = tx_bytes_from_edges(b.edges, clk_hz, baud);
  for (size_t k = 0; k < std::min(ta.size(), tb.size()); ++k) {
    if (ta[k] != tb[k]) {
      return fmt::format("answer byte #{}: {} 0x{:02X} at cycle {}, {} 0x{:02X} at cycle {}", k,
                         a.model, ta[k].second, ta[k].first, b.model, tb[k].second, tb[k].first);
    }
  }
  if (ta.size() != tb.size()) {
    return fmt::format("answer bytes on TX: {} {}, {} {}", a.model, ta.size(), b.model, tb.size());
  }
  for (size_t k = 0; k < std::min(a.edges.size(), b.edges.size()); ++k) {
    const auto& x = a.edges[k];
    const auto& y = b.edges[k];
    if (x.cycle != y.cycle || x.signal != y.signal || x.value != y.value) {
      return fmt::format("edge #{}: {} {}, {} {}", k, a.model, describe(x), b.model, describe(y));
    }
  }
  if (a.edges.size() != b.edges.size()) {
    const auto& longer = a.edges.size() > b.edges.size() ? a : b;
    const size_t k = std::min(a.edges.size(), b.edges.size());
    return fmt::format("edges: {} {}, {} {}; first extra edge #{} ({}): {}", a.model,
                       a.edges.size(), b.model, b.edges.size(), k, longer.model,
                       describe(longer.edges[k]));
  }
  if (a.received != b.received) {
    size_t k = 0;
    while (k < a.received.size() && k < b.received.size() && a.received[k] == b.received[k]) ++k;
    return fmt::format("bytes read by the host differ from #{} ({} {}, {} {} bytes)", k, a.model,
                       a.received.size(), b.model, b.received.size());
  }
  return "";
}

}  // namespace fpgacnc::twins
