#include "cutter_comp.h"

#include <cmath>
#include <variant>

namespace fpgacnc::gcode {
namespace {

// Corners whose direction changes by at most this much (radians) get neither an intersection
// nor an arc: the next move starts where the last one ended (LinuxCNC's tolerance, 0.05 rad).
constexpr double kSmallTurn = 0.05;
constexpr double kEps = 1e-9;

void set_line(Command& c, int line) {
  std::visit([line](auto& x) { x.line = line; }, c);
}

}  // namespace

CutterComp::P2 CutterComp::uv(const Vec4& p) const {
  return {p[static_cast<size_t>(u_)], p[static_cast<size_t>(v_)]};
}

void CutterComp::set_uv(Vec4& p, P2 q) const {
  p[static_cast<size_t>(u_)] = q.x;
  p[static_cast<size_t>(v_)] = q.y;
}

// Unit direction of travel at `at` (a point of the path).
CutterComp::P2 CutterComp::tangent(const Seg& s, P2 at) const {
  if (!s.arc) {
    const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y, d = std::hypot(dx, dy);
    return {dx / d, dy / d};
  }
  const double rx = at.x - s.c.x, ry = at.y - s.c.y, d = std::hypot(rx, ry);
  return {-s.dir * ry / d, s.dir * rx / d};
}

// Left of a counter-clockwise arc is its centre: the offset path's radius shrinks there.
double CutterComp::offset_radius(const Seg& s, bool at_end) const {
  if (s.tool_path) return s.radius;
  return (at_end ? s.radius_end : s.radius) - sign_ * s.dir * r_;
}

CutterComp::P2 CutterComp::offset_point(const Seg& s, P2 at) const {
  if (s.arc) {  // along the radius through `at`, by the tool radius
    const double d = std::hypot(at.x - s.c.x, at.y - s.c.y);
    const double k = s.tool_path ? s.radius / d : (d - sign_ * s.dir * r_) / d;
    return {s.c.x + (at.x - s.c.x) * k, s.c.y + (at.y - s.c.y) * k};
  }
  const P2 t = tangent(s, at);
  return {at.x - sign_ * r_ * t.y, at.y + sign_ * r_ * t.x};
}

// Where the offset paths of s0 and s1 cross (false when they do not). Of two crossings, the one
// LinuxCNC takes: for a line and an arc, the one behind the arc's centre along the line when the
// tool is inside the arc, ahead of it when outside (the line coming first: the other way
// round); for two arcs, the one to the left of the line from the first centre to the second
// when the tool is inside the first arc and the second runs counter-clockwise, or outside and
// clockwise.
bool CutterComp::intersect(const Seg& s0, const Seg& s1, P2& hit) const {
  P2 cand[2];
  int n = 0;
  // A line's offset: a point and a unit direction; an arc's: centre and radius.
  auto line_of = [&](const Seg& s, P2& q, P2& d) {
    d = tangent(s, s.a);
    q = offset_point(s, s.a);
  };
  auto line_circle = [&](P2 q, P2 d, P2 c, double rad) {
    const double fx = q.x - c.x, fy = q.y - c.y;
    const double b = fx * d.x + fy * d.y, cc = fx * fx + fy * fy - rad * rad;
    const double disc = b * b - cc;
    if (disc < 0) return;
    const double sq = std::sqrt(disc);
    for (double t : {-b - sq, -b + sq}) cand[n++] = {q.x + t * d.x, q.y + t * d.y};
  };
  if (!s0.arc && !s1.arc) {
    P2 q0, d0, q1, d1;
    line_of(s0, q0, d0);
    line_of(s1, q1, d1);
    const double den = d0.x * d1.y - d0.y * d1.x;
    if (std::fabs(den) < kEps) return false;
    const double t = ((q1.x - q0.x) * d1.y - (q1.y - q0.y) * d1.x) / den;
    hit = {q0.x + t * d0.x, q0.y + t * d0.y};
    return true;
  }
  auto inside = [&](const Seg& a) { return sign_ * a.dir > 0; };
  if (s0.arc != s1.arc) {
    const Seg& ln = s0.arc ? s1 : s0;
    const Seg& ar = s0.arc ? s0 : s1;
    P2 q, d;
    line_of(ln, q, d);
    line_circle(q, d, ar.c, offset_radius(ar, &ar == &s0));
    if (n == 0) return false;
    // cand[0] lies before cand[1] along the line.
    const bool ahead = s0.arc ? !inside(ar) : inside(ar);
    const double along0 = (cand[0].x - ar.c.x) * d.x + (cand[0].y - ar.c.y) * d.y;
    const double along1 = (cand[1].x - ar.c.x) * d.x + (cand[1].y - ar.c.y) * d.y;
    hit = (along0 > along1) == ahead ? cand[0] : cand[1];
    return true;
  } else {
    const double r0 = offset_radius(s0, true), r1 = offset_radius(s1);
    const double dx = s1.c.x - s0.c.x, dy = s1.c.y - s0.c.y, d = std::hypot(dx, dy);
    if (d < kEps || d > r0 + r1 || d < std::fabs(r0 - r1)) return false;
    const double a = (r0 * r0 - r1 * r1 + d * d) / (2 * d);
    const double h = std::sqrt(std::max(0.0, r0 * r0 - a * a));
    const double mx = s0.c.x + a * dx / d, my = s0.c.y + a * dy / d;
    const bool left = inside(s0) == (s1.dir > 0);
    hit = left ? P2{mx - h * dy / d, my + h * dx / d} : P2{mx + h * dy / d, my - h * dx / d};
    return true;
  }
}

// The angle an arc about c turns through from a to b in direction dir (+1 CCW), (0, 2 pi].
double CutterComp::sweep_of(P2 c, P2 a, P2 b, int dir) {
  double t = (std::atan2(b.y - c.y, b.x - c.x) - std::atan2(a.y - c.y, a.x - c.x)) * dir;
  while (t <= 0) t += 2 * M_PI;
  while (t > 2 * M_PI) t -= 2 * M_PI;
  return t;
}

void CutterComp::start(Side side, double radius, Plane plane, const Vec4& pos) {
  if (on_) throw Error("cutter radius compensation is already on (G40 first)");
  if (plane == Plane::kYZ)
    throw Error("cutter radius compensation needs the XY or XZ plane (G17 or G18), not G19");
  sign_ = side == Side::kLeft ? 1 : -1;
  if (radius < 0) sign_ = -sign_;
  r_ = std::fabs(radius);
  plane_ = plane;
  const PlaneAxes pa = plane_axes(plane);
  u_ = pa.u;
  v_ = pa.v;
  if (!exiting_) cur_ = pos;
  exiting_ = false;
  on_ = true;
  entry_ = true;
}

void CutterComp::stop(std::vector<Command>& out, int line) {
  if (!on_) return;
  if (!queue_.empty()) move_pending_end(uv(cur_));  // the last move must still run forwards
  flush(out, line);
  on_ = false;
  exiting_ = true;
}

void CutterComp::flush(std::vector<Command>& out, int line) {
  for (auto& c : queue_) {
    set_line(c, line);
    out.push_back(std::move(c));
  }
  queue_.clear();
}

void CutterComp::process(std::vector<Command>& cmds, std::vector<Command>& out, int line) {
  for (auto& c : cmds) {
    if (auto* mv = std::get_if<Move>(&c))
      move(*mv, out, line);
    else if (queue_.empty())
      out.push_back(std::move(c));
    else
      queue_.push_back(std::move(c));
  }
}

void CutterComp::move_pending_end(P2 hit) {
  Move& pm = std::get<Move>(queue_[0]);
  const P2 s = uv(pm.start);
  if (pending_.arc) {
    // From the tool's start to the new end, the arc may turn 0.254 rad more than programmed
    // (LinuxCNC's allowance); more means the path crossed itself.
    if (!pending_entry_ && pm.extra_turns == 0 &&
        sweep_of(pending_.c, s, hit, pending_.dir) > pending_.sweep + 0.254)
      throw Error(
          "arc in a concave corner: the tool cannot follow it without gouging (the tool is too "
          "large for this corner)");
    if (std::hypot(hit.x - uv(pm.end).x, hit.y - uv(pm.end).y) > kEps) pm.full_circle = false;
  } else {
    const P2 t = tangent(pending_, pending_.a);
    if (!pending_entry_ && (hit.x - s.x) * t.x + (hit.y - s.y) * t.y < 0)
      throw Error(
          "straight move in a concave corner: the tool cannot reach the corner without gouging "
          "(the tool is too large for this corner)");
  }
  for (auto& c : queue_)
    if (auto* m = std::get_if<Move>(&c)) {
      if (m != &pm) set_uv(m->start, hit);
      set_uv(m->end, hit);
    }
  set_uv(cur_, hit);
}

void CutterComp::move(Move mv, std::vector<Command>& out, int line) {
  const bool arc = mv.motion == Motion::kArcCw || mv.motion == Motion::kArcCcw;
  if (exiting_) {
    if (arc)
      throw Error(
          "the move after G40 (the exit from cutter radius compensation) must be a straight "
          "line, not an arc");
    exiting_ = false;
    mv.start = cur_;
    cur_ = mv.end;
    out.push_back(mv);
    return;
  }
  if (!on_) {
    cur_ = mv.end;
    out.push_back(mv);
    return;
  }
  if (arc && mv.plane != plane_)
    throw Error("an arc in another plane than the one cutter radius compensation was turned on in");
  Seg s;
  s.a = uv(mv.start);
  s.b = uv(mv.end);
  s.arc = arc;
  if (arc) {
    s.c = {mv.center[0], mv.center[1]};
    s.radius = std::hypot(s.a.x - s.c.x, s.a.y - s.c.y);
    s.radius_end = std::hypot(s.b.x - s.c.x, s.b.y - s.c.y);
    s.dir = mv.motion == Motion::kArcCcw ? 1 : -1;
    s.sweep = sweep_of(s.c, s.a, s.b, s.dir);
  }
  const bool in_plane = arc || std::hypot(s.b.x - s.a.x, s.b.y - s.a.y) > kEps;
  if (entry_ && arc) {
    // An entry arc ends at the offset of its programmed end; its centre moves along the radius
    // through that end until it is as far from the tool's start as from the end (LinuxCNC).
    const double rr = offset_radius(s, true);
    if (rr <= kEps)
      throw Error(
          "arc radius not larger than the tool radius on the inside of the arc: the tool cannot "
          "follow it");
    const P2 st = uv(cur_);
    const P2 u{(s.b.x - s.c.x) / s.radius_end, (s.b.y - s.c.y) / s.radius_end};
    const double cx = s.c.x - st.x, cy = s.c.y - st.y;
    const double den = 2 * (u.x * cx + u.y * cy + rr);
    if (std::fabs(den) < kEps)
      throw Error("entry arc of cutter radius compensation: no arc from the tool to its end");
    const double t = (rr * rr - cx * cx - cy * cy) / den;
    Seg e;
    e.arc = true;
    e.tool_path = true;
    e.dir = s.dir;
    e.a = st;
    e.b = {s.c.x + rr * u.x, s.c.y + rr * u.y};
    e.c = {s.c.x + t * u.x, s.c.y + t * u.y};
    e.radius = std::fabs(rr - t);
    mv.start = cur_;
    set_uv(mv.end, e.b);
    mv.center = {e.c.x, e.c.y};
    mv.full_circle = false;
    cur_ = mv.end;
    queue_.clear();
    queue_.emplace_back(mv);
    pending_ = e;
    pending_entry_ = true;
    entry_ = false;
    return;
  }
  if (entry_) {
    if (!in_plane || std::hypot(s.b.x - s.a.x, s.b.y - s.a.y) <= r_)
      throw Error(
          "the entry move of cutter radius compensation (the first move after G41/G42) must be "
          "longer in the plane than the tool radius");
    mv.start = cur_;
    set_uv(mv.end, offset_point(s, s.b));
    cur_ = mv.end;
    queue_.clear();
    queue_.emplace_back(mv);
    pending_ = s;
    pending_entry_ = true;
    entry_ = false;
    return;
  }
  if (!in_plane) {  // along the third axis only: from the offset point, held with the move before
    mv.start = cur_;
    set_uv(mv.end, uv(cur_));
    cur_ = mv.end;
    if (queue_.empty())
      out.push_back(mv);
    else
      queue_.emplace_back(mv);
    return;
  }
  if (arc && offset_radius(s) <= kEps)
    throw Error(
        "arc radius not larger than the tool radius on the inside of the arc: the tool cannot "
        "follow it");
  const P2 t0 = tangent(pending_, pending_.b);
  const P2 t1 = tangent(s, s.a);
  // Turn from the last move to this one, > 0 to the left; times the side: > 0 turns towards
  // the tool (an inside corner), < 0 away from it (outside).
  const double turn = sign_ * std::atan2(t0.x * t1.y - t0.y * t1.x, t0.x * t1.x + t0.y * t1.y);
  // LinuxCNC's corner angle: beta = -turn in [-pi/2, 3pi/2). Inside when it turns towards the
  // tool by more than the tolerance and less than a reversal.
  double beta = -turn;
  if (beta < -M_PI / 2) beta += 2 * M_PI;
  // "h" and "m" shapes: an almost reversal counts as inside when the tool runs outside of the
  // arc (the last one, before a line; the next one, before an arc), as LinuxCNC keeps it there.
  const bool reversal_inside =
      arc ? std::fabs(beta - M_PI) < kSmallTurn && sign_ * s.dir < 0
          : beta > M_PI - kSmallTurn && pending_.arc && sign_ * pending_.dir < 0;
  const bool concave = beta < -kSmallTurn || beta > M_PI + kSmallTurn || reversal_inside;
  if (concave) {
    P2 hit;
    if (!intersect(pending_, s, hit))
      throw Error(
          "concave corner: the offset paths do not meet (the tool is too large for this "
          "corner)");
    move_pending_end(hit);
    flush(out, line);
  } else if (beta > kSmallTurn) {
    if (!arc) move_pending_end(uv(cur_));  // the end stays; it must still run forwards
    flush(out, line);
    Move corner = mv;
    corner.start = cur_;
    corner.end = cur_;
    set_uv(corner.end, offset_point(s, s.a));
    corner.extra_turns = 0;
    corner.full_circle = false;
    if (mv.motion != Motion::kRapid) {
      corner.motion = sign_ > 0 ? Motion::kArcCw : Motion::kArcCcw;
      corner.plane = plane_;
      corner.center = {s.a.x, s.a.y};
    }
    corner.line = line;
    cur_ = corner.end;
    out.push_back(corner);
  } else {
    flush(out, line);
  }
  mv.start = cur_;
  set_uv(mv.end, offset_point(s, s.b));
  if (arc)
    mv.full_circle =
        std::hypot(uv(mv.end).x - uv(mv.start).x, uv(mv.end).y - uv(mv.start).y) < kEps;
  cur_ = mv.end;
  queue_.emplace_back(mv);
  pending_ = s;
  pending_entry_ = false;
}

}  // namespace fpgacnc::gcode
