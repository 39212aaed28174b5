#include "fpgacnc/link/stream_v1.h"

#include <fmt/format.h>

#include "fpgacnc/protocol/v1.h"

namespace fpgacnc::link {

StreamReport stream_v1(Link& link, const plan::Plan& plan, const StreamOptions& options) {
  namespace v1 = protocol::v1;
  // Pack everything first: a plan v1 cannot carry throws here, before any byte is written.
  const v1::Job job = v1::pack_job(plan);
  StreamReport rep;
  rep.skipped_heater = job.skipped_heater;
  rep.ze_only = job.ze_only;
  const auto t0 = std::chrono::steady_clock::now();

  link.flush_input();
  link.write(job.init);
  rep.bytes_written += job.init.size();

  long last_acked_index = -1;
  int last_acked_line = 0;
  for (const auto& st : job.steps) {
    if (st.is_dwell) {
      // Link time: wall time on a port, board clocks on a simulated board (link.h).
      link.wait_until(link.now() + std::chrono::duration_cast<Link::Time>(
                                       std::chrono::duration<double>(st.dwell_s)));
      ++rep.dwells;
      continue;
    }
    link.write(st.packet);
    rep.bytes_written += st.packet.size();
    ++rep.moves;
    const Link::Time deadline = link.now() + options.ack_timeout;
    for (;;) {
      const std::optional<uint8_t> b = link.read_byte_until(deadline);
      if (!b) {
        const std::string last =
            last_acked_index < 0
                ? std::string("none")
                : fmt::format("segment {} (line {})", last_acked_index, last_acked_line);
        throw Error(fmt::format(
            "{}: no ACK (0xAA) within {:.3g} s{} for segment {} (line {}); last acknowledged "
            "move: {}",
            link.name(), static_cast<double>(options.ack_timeout.count()) / 1000.0,
            link.board_clock() ? " of board time" : "", st.segment_index, st.source_line, last));
      }
      if (*b == v1::kAck) break;
      ++rep.warnings;
      if (options.unexpected_byte) options.unexpected_byte(*b);
    }
    ++rep.acks;
    last_acked_index = static_cast<long>(st.segment_index);
    last_acked_line = st.source_line;
    if (options.progress) options.progress(rep.moves, job.motions);
  }
  rep.elapsed = std::chrono::steady_clock::now() - t0;
  rep.final_steps = plan.final_steps;
  rep.final_mm = plan.final_mm;
  return rep;
}

StreamReport stream_file_v1(Link& link, const std::string& path, const config::MachineConfig& cfg,
                            const StreamOptions& options) {
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const plan::Plan p = plan::plan_input_file(path, cfg, po);
  return stream_v1(link, p, options);
}

}  // namespace fpgacnc::link
