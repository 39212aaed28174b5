// The host codec against spec/vectors.txt (generated from spec/protocol.toml; the Verilated
// frame_decoder bench and the twin codec test read the same frames): every frame parses (or is
// rejected for its CRC), decodes to the stated fields, is rebuilt byte-exact by the builders, and
// check_host_frame gives the stated device answer.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/protocol/v2.h"
#include "fpgacnc/spec_vectors.h"

namespace {

namespace v2 = fpgacnc::protocol::v2;
namespace spec = fpgacnc::spec;

std::vector<v2::Frame> parse_all(const std::vector<uint8_t>& bytes, v2::FrameParser& p) {
  p.feed(bytes);
  std::vector<v2::Frame> out;
  while (auto f = p.next()) out.push_back(*f);
  return out;
}

std::vector<int32_t> steps_of(const std::vector<int64_t>& v) {
  return std::vector<int32_t>(v.begin(), v.end());
}

// Decodes a good frame by its type, compares the fields and rebuilds it with the builders.
void check_fields(const spec::Vector& v, const v2::Frame& f) {
  const std::string at = v.name;
  std::vector<uint8_t> rebuilt;
  switch (static_cast<v2::Type>(v.type)) {
    case v2::Type::Hello:
      rebuilt = v2::encode(v2::hello(v.seq));
      break;
    case v2::Type::StatusQuery:
      rebuilt = v2::encode(v2::status_query(v.seq));
      break;
    case v2::Type::ConfigAxis: {
      const auto c = v2::decode_config_axis(f, 4);
      EXPECT_EQ(c.axis, v.field("axis")) << at;
      EXPECT_EQ(c.step_high, v.field("step_high")) << at;
      EXPECT_EQ(c.step_low, v.field("step_low")) << at;
      EXPECT_EQ(c.dir_setup, v.field("dir_setup")) << at;
      EXPECT_EQ(c.dir_hold, v.field("dir_hold")) << at;
      rebuilt = v2::encode(
          v2::config_axis(v.seq, c.axis, c.step_high, c.step_low, c.dir_setup, c.dir_hold));
      break;
    }
    case v2::Type::Numerators: {
      const auto n = v2::decode_numerators(f);
      EXPECT_EQ(n[0], v.field("numerator_x")) << at;
      EXPECT_EQ(n[1], v.field("numerator_y")) << at;
      rebuilt = v2::encode(v2::numerators(v.seq, n[0], n[1]));
      break;
    }
    case v2::Type::Line: {
      const auto l = v2::decode_line(f, 4);
      EXPECT_EQ(l.code, v.field("code")) << at;
      EXPECT_EQ(l.power, v.field("power")) << at;
      EXPECT_EQ(l.t, v.field("t")) << at;
      EXPECT_EQ(l.short_steps, v.field("short") != 0) << at;
      EXPECT_EQ(l.steps, steps_of(v.list("steps"))) << at;
      rebuilt = v2::encode(
          v2::line(v.seq, l.code, l.power, l.t, steps_of(v.list("steps")), v.field("short") != 0));
      break;
    }
    case v2::Type::Dwell:
      EXPECT_EQ(v2::decode_dwell(f), v.field("t")) << at;
      rebuilt = v2::encode(v2::dwell(v.seq, static_cast<uint32_t>(v.field("t"))));
      break;
    case v2::Type::LineProfile: {
      const auto p = v2::decode_line_profile(f, 4);
      EXPECT_EQ(p.code, v.field("code")) << at;
      EXPECT_EQ(p.power, v.field("power")) << at;
      EXPECT_EQ(p.short_steps, v.field("short") != 0) << at;
      EXPECT_EQ(p.v_entry, static_cast<uint64_t>(v.field("v_entry"))) << at;
      EXPECT_EQ(p.v_cruise, static_cast<uint64_t>(v.field("v_cruise"))) << at;
      EXPECT_EQ(p.v_exit, static_cast<uint64_t>(v.field("v_exit"))) << at;
      EXPECT_EQ(p.accel, v.field("accel")) << at;
      EXPECT_EQ(p.decel_at, v.field("decel_at")) << at;
      EXPECT_EQ(p.steps, steps_of(v.list("steps"))) << at;
      rebuilt = v2::encode(v2::line_profile(v.seq, p, v.field("short") != 0));
      break;
    }
    case v2::Type::Arc: {
      const auto a = v2::decode_arc(f);
      EXPECT_EQ(a.code, v.field("code")) << at;
      EXPECT_EQ(a.power, v.field("power")) << at;
      EXPECT_EQ(static_cast<int>(a.plane), v.field("plane")) << at;
      EXPECT_EQ(a.i, v.field("i")) << at;
      EXPECT_EQ(a.j, v.field("j")) << at;
      EXPECT_EQ(a.dx, v.field("dx")) << at;
      EXPECT_EQ(a.dy, v.field("dy")) << at;
      EXPECT_EQ(a.dz, v.field("dz")) << at;
      EXPECT_EQ(a.n_ramp, v.field("n_ramp")) << at;
      EXPECT_EQ(a.c_total, static_cast<uint64_t>(v.field("c_total"))) << at;
      EXPECT_EQ(a.v_entry, static_cast<uint64_t>(v.field("v_entry"))) << at;
      EXPECT_EQ(a.v_cruise, static_cast<uint64_t>(v.field("v_cruise"))) << at;
      EXPECT_EQ(a.v_exit, static_cast<uint64_t>(v.field("v_exit"))) << at;
      EXPECT_EQ(a.accel, static_cast<uint64_t>(v.field("accel"))) << at;
      EXPECT_EQ(a.decel_at, static_cast<uint64_t>(v.field("decel_at"))) << at;
      rebuilt = v2::encode(v2::arc(v.seq, a));
      break;
    }
    case v2::Type::Output: {
      const auto o = v2::decode_output(f);
      // The stated mask / value / duty, rebuilt from the decoded set.
      uint8_t mask = 0, value = 0;
      auto put = [&](const std::optional<bool>& level, uint8_t bit) {
        if (!level) return;
        mask |= bit;
        if (*level) value |= bit;
      };
      put(o.flood, v2::kOutFlood);
      put(o.mist, v2::kOutMist);
      if (o.fan) mask |= v2::kOutFan;
      for (size_t n = 0; n < v2::kDigitalOutputs; ++n)
        put(o.dout[n], static_cast<uint8_t>(v2::kOutDout0 << n));
      EXPECT_EQ(mask, v.field("mask")) << at;
      EXPECT_EQ(value, v.field("value")) << at;
      EXPECT_EQ(o.fan.value_or(0), v.field("duty")) << at;
      rebuilt = v2::encode(v2::output_frame(v.seq, o));
      break;
    }
    case v2::Type::Ack: {
      const auto c = v2::decode_credit(f);
      EXPECT_EQ(c.next_seq, v.field("next_seq")) << at;
      EXPECT_EQ(c.free, v.field("free")) << at;
      EXPECT_EQ(c.done, v.field("done")) << at;
      rebuilt = v2::encode(v2::ack(v.seq, c));
      break;
    }
    case v2::Type::Nak: {
      const auto n = v2::decode_nak(f);
      EXPECT_EQ(n.seq, v.field("seq")) << at;
      EXPECT_EQ(static_cast<int>(n.reason), v.field("reason")) << at;
      EXPECT_EQ(n.next_seq, v.field("next_seq")) << at;
      EXPECT_EQ(n.free, v.field("free")) << at;
      rebuilt = v2::encode(v2::nak(v.seq, n));
      break;
    }
    default:
      ADD_FAILURE() << at << ": no decoder for type " << v.type_name;
      return;
  }
  EXPECT_EQ(v2::hex(rebuilt), v2::hex(v.bytes)) << at << ": rebuilt by the host's builders";
}

TEST(SpecVectors, HostCodec) {
  const auto vectors = spec::load_vectors();
  ASSERT_GE(vectors.size(), 10u);
  size_t decoded = 0, answered = 0;
  for (const auto& v : vectors) {
    SCOPED_TRACE(v.name + ": " + v.doc);
    v2::FrameParser p;
    const auto frames = parse_all(v.bytes, p);
    const bool bad_crc = v.has_answer && v.answer == "NAK" &&
                         v.answer_value == static_cast<uint8_t>(v2::NakReason::BadCrc);
    if (bad_crc) {
      EXPECT_TRUE(frames.empty());
      EXPECT_EQ(p.crc_errors(), 1u);
      continue;
    }
    ASSERT_EQ(frames.size(), 1u);
    const auto& f = frames[0];
    EXPECT_EQ(f.seq, v.seq);
    EXPECT_EQ(f.type, v.type);
    EXPECT_EQ(v2::type_name(f.type),
              v.type_name == "UNKNOWN" ? v2::type_name(f.type) : v.type_name);
    if (!v.has_answer || v.answer != "NAK") {
      check_fields(v, f);
      ++decoded;
    }
    if (v.has_answer) {
      const auto r = v2::check_host_frame(f, 4);
      if (v.answer == "NAK") {
        ASSERT_TRUE(r.has_value()) << "expected NAK " << v.nak_name;
        EXPECT_EQ(static_cast<uint8_t>(*r), v.answer_value);
        EXPECT_EQ(v2::nak_reason_name(static_cast<uint8_t>(*r)), v.nak_name);
      } else {
        EXPECT_FALSE(r.has_value()) << "NAK " << v2::nak_reason_name(static_cast<uint8_t>(*r));
        const bool fifo = v2::is_fifo(f.type);
        EXPECT_EQ(fifo, v.has_entry()) << "a FIFO frame states its entry";
        if (v.answer == "IDENT") {
          EXPECT_EQ(f.type, static_cast<uint8_t>(v2::Type::Hello));
        } else if (v.answer == "STATUS") {
          EXPECT_EQ(f.type, static_cast<uint8_t>(v2::Type::StatusQuery));
        } else {
          EXPECT_EQ(v.answer, "ACK");
          EXPECT_TRUE(v2::is_sequenced(f.type));
        }
      }
      ++answered;
    }
  }
  EXPECT_GE(decoded, 10u);
  EXPECT_GE(answered, 10u);
}

// The ARC worked frames against the integer reference walk (fpgacnc/models/arc_walk.h, the walk the
// device runs): with the frame's N_RAMP the walk lands on the end point in its first pass (summed
// angle = the swept angle) with total cost C_TOTAL, the host's choice of N_RAMP (arc::plan) is the
// frame's, and the profile fields end the recurrence at V_exit. One frame has R0 != R1 (the
// radius-squared ramp of docs/protocol.md "ARC").
TEST(SpecVectors, ArcFramesMatchTheReferenceWalk) {
  namespace arc = fpgacnc::models::arc;
  size_t arcs = 0, ramps = 0;
  for (const auto& v : spec::load_vectors()) {
    if (v.type != static_cast<uint8_t>(v2::Type::Arc) || !v.has_answer || v.answer != "ACK")
      continue;
    SCOPED_TRACE(v.name + ": " + v.doc);
    arc::Geometry g;
    g.i = static_cast<int32_t>(v.field("i"));
    g.j = static_cast<int32_t>(v.field("j"));
    g.dx = static_cast<int32_t>(v.field("dx"));
    g.dy = static_cast<int32_t>(v.field("dy"));
    g.ccw = v.field("code") == 3;
    const auto n_ramp = static_cast<uint32_t>(v.field("n_ramp"));
    const auto c_total = static_cast<uint64_t>(v.field("c_total"));
    const arc::WalkResult w = arc::walk(g, n_ramp);
    EXPECT_TRUE(w.reached);
    EXPECT_EQ(w.c_total, c_total);
    EXPECT_NEAR(arc::walked_angle(g, w.moves), arc::sweep(g), 1e-6) << "first pass";
    const arc::Plan p = arc::plan(g);
    EXPECT_TRUE(p.ok);
    EXPECT_EQ(p.n_ramp, n_ramp);
    EXPECT_EQ(p.c_total, c_total);
    const fpgacnc::plan::Recurrence r{c_total,
                                      static_cast<uint64_t>(v.field("v_entry")),
                                      static_cast<uint64_t>(v.field("v_cruise")),
                                      static_cast<uint64_t>(v.field("v_exit")),
                                      static_cast<uint64_t>(v.field("accel")),
                                      static_cast<uint64_t>(v.field("decel_at"))};
    EXPECT_EQ(fpgacnc::plan::simulate_recurrence(r).v_last, r.v_exit);
    const int64_t r0 = int64_t{g.i} * g.i + int64_t{g.j} * g.j;
    const int64_t r1 = int64_t{g.dx - g.i} * (g.dx - g.i) + int64_t{g.dy - g.j} * (g.dy - g.j);
    ramps += r0 != r1;
    ++arcs;
  }
  EXPECT_GE(arcs, 2u);
  EXPECT_GE(ramps, 1u);
}

// The reader names file:line:column for a bad vector file.
TEST(SpecVectors, ReaderNamesTheBadLine) {
  const std::string path = ::testing::TempDir() + "bad_vectors.txt";
  {
    std::ofstream o(path);
    o << "# comment\nvector x\nbytes A5 0G\nend\n";
  }
  try {
    spec::load_vectors(path);
    ADD_FAILURE() << "no error for a bad byte";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path + ":3:10: not a number: \"0G\"");
  }
}

}  // namespace
