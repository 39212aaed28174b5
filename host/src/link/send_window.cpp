#include "fpgacnc/link/send_window.h"

#include <algorithm>
#include <cmath>

namespace fpgacnc::link {

using std::chrono::milliseconds;

SendWindow::SendWindow(Options options, uint8_t seq0, Time now)
    : opt_(options),
      seq0_(seq0),
      cwnd_(static_cast<double>(std::max<size_t>(options.max_unacked, 1))),
      ssthresh_(cwnd_),
      max_window_(cwnd_),
      rto_(options.min_rto),
      last_progress_(now),
      max_rto_s_(std::chrono::duration<double>(options.min_rto).count()),
      min_window_(std::max<size_t>(options.max_unacked, 1)) {}

milliseconds SendWindow::base_rto() const {
  const auto est = std::chrono::duration<double>(srtt_ + 4.0 * rttvar_);
  return std::max(opt_.min_rto,
                  std::chrono::duration_cast<milliseconds>(have_rtt_ ? est : est.zero()));
}

bool SendWindow::may_send(size_t limit) const {
  const size_t lim = probing_ ? std::min(limit, acked_ + 1) : limit;
  return sent_ < lim && sent_ - acked_ < window();
}

bool SendWindow::mark_sent(Time now) {
  if (sent_at_.size() <= sent_) {
    sent_at_.resize(sent_ + 1);
    sends_.resize(sent_ + 1, 0);
  }
  const bool resend = sent_ < high_;
  if (resend) ++retransmissions_;
  sent_at_[sent_] = now;
  if (sends_[sent_] < UINT16_MAX) ++sends_[sent_];
  ++sent_;
  high_ = std::max(high_, sent_);
  return resend;
}

std::optional<size_t> SendWindow::acknowledge(uint8_t next_seq, Time now) {
  const size_t delta = static_cast<uint8_t>(next_seq - seq_of(acked_));
  if (delta > high_ - acked_) return std::nullopt;  // behind us, or ahead of anything sent
  if (delta == 0) return 0;
  acked_ += delta;
  if (sent_ < acked_) sent_ = acked_;  // acknowledged beyond a go-back point
  last_progress_ = now;
  if (sends_[acked_ - 1] == 1) {
    const double r = std::chrono::duration<double>(now - sent_at_[acked_ - 1]).count();
    if (!have_rtt_) {
      srtt_ = r;
      rttvar_ = r / 2.0;
      have_rtt_ = true;
    } else {
      rttvar_ = 0.75 * rttvar_ + 0.25 * std::fabs(srtt_ - r);
      srtt_ = 0.875 * srtt_ + 0.125 * r;
    }
  }
  rto_ = base_rto();
  max_rto_s_ = std::max(max_rto_s_, std::chrono::duration<double>(rto_).count());
  probing_ = false;
  for (size_t k = 0; k < delta; ++k) cwnd_ += cwnd_ < ssthresh_ ? 1.0 : 1.0 / cwnd_;
  cwnd_ = std::min(cwnd_, max_window_);
  goback_same_ = 0;
  if (goback_at_ && acked_ > *goback_at_) goback_at_.reset();
  return delta;
}

size_t SendWindow::go_back(Time now) {
  if (goback_at_ && acked_ == *goback_at_) {
    ++goback_same_;
  } else {
    goback_same_ = 0;
  }
  sent_ = acked_;
  goback_at_ = acked_;
  ++go_backs_;
  ssthresh_ = std::max(2.0, cwnd_ / 2.0);
  cwnd_ = ssthresh_;
  min_window_ = std::min(min_window_, window());
  last_progress_ = now;
  probing_ = false;
  return goback_same_;
}

bool SendWindow::timer_expired(Time now) const {
  return sent_ > acked_ && now - std::max(last_progress_, sent_at_[acked_]) > rto_;
}

size_t SendWindow::on_timeout(Time now) {
  ++timeouts_;
  const size_t same = go_back(now);
  probing_ = true;
  rto_ = std::min(rto_ * 2, base_rto() * 8);
  max_rto_s_ = std::max(max_rto_s_, std::chrono::duration<double>(rto_).count());
  return same;
}

}  // namespace fpgacnc::link
