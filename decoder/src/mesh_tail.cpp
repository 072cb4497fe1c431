// vds client library: the single-rate tail of a progressive mesh stream
// (docs/mesh-codec.md, "The single-rate tail"): an Edgebreaker traversal
// (Rossignac 1999) rebuilds the corner table triangle by triangle, with the
// S vertex located by a border walk, and the positions are predicted from
// parallelograms across already decoded neighbours.
#include "vds/mesh.h"

namespace vds {

void TailContexts::reset() { arith_init_contexts(c, kCount); }

Status MeshTail::begin(MeshState& m, Arena& arena, const TailCounts& n) {
  m_ = &m;
  n_ = n;
  built_ = real_v_ = dummy_v_ = real_t_ = dummy_t_ = 0;
  gate_ = x_ = y_ = kMeshNone;
  fan_x_ = fan_y_ = depth_ = live_ = peak_ = 0;
  const uint64_t v = uint64_t{n.vertices} + n.dummy_vertices;
  const uint64_t t = uint64_t{n.triangles} + n.dummy_triangles;
  if (n.vertices < 3 || n.triangles < 1 || v > m.cap_v_ || t > m.cap_t_ || n.max_border < 3 ||
      n.max_border > 3 * t)
    return Status::malformed;
  corner_ = arena.alloc_array<uint32_t>(n.max_border);
  next_ = arena.alloc_array<uint32_t>(n.max_border);
  prev_ = arena.alloc_array<uint32_t>(n.max_border);
  if (corner_ == nullptr || next_ == nullptr || prev_ == nullptr) return Status::workspace_too_small;
  // Every edge free, chained through next_.
  for (uint32_t e = 0; e < n.max_border; ++e) next_[e] = e + 1 < n.max_border ? e + 1 : kMeshNone;
  free_ = 0;
  for (uint64_t i = 0; i < v; ++i) m.pos_[3 * i] = 0;  // triangles built around each vertex
  m.nv_ = 0;
  m.nt_ = 0;
  return Status::ok;
}

uint32_t MeshTail::new_edge(uint32_t corner) {
  const uint32_t e = free_;
  if (e == kMeshNone) return kMeshNone;
  free_ = next_[e];
  corner_[e] = corner;
  if (++live_ > peak_) peak_ = live_;
  return e;
}

void MeshTail::free_edge(uint32_t e) {
  next_[e] = free_;
  free_ = e;
  --live_;
}

Status MeshTail::new_vertex(bool dummy, uint32_t* v) {
  if (dummy) {
    if (dummy_v_ >= n_.dummy_vertices) return Status::malformed;
    *v = n_.vertices + dummy_v_++;
  } else {
    if (real_v_ >= n_.vertices) return Status::malformed;
    *v = real_v_++;
  }
  return Status::ok;
}

Status MeshTail::new_triangle(uint32_t a, uint32_t b, uint32_t c, uint32_t* t) {
  const bool dummy = a >= n_.vertices || b >= n_.vertices || c >= n_.vertices;
  if (dummy) {
    if (dummy_t_ >= n_.dummy_triangles) return Status::malformed;
    *t = n_.triangles + dummy_t_++;
  } else {
    if (real_t_ >= n_.triangles) return Status::malformed;
    *t = real_t_++;
  }
  const uint32_t c0 = 3 * *t;
  const uint32_t v[3] = {a, b, c};
  for (uint32_t k = 0; k < 3; ++k) {
    m_->corner_vertex_.set(c0 + k, v[k]);
    m_->set_opp(c0 + k, -1);
    uint16_t& fan = m_->pos_[3 * v[k]];
    if (fan != 0xFFFFu) ++fan;
  }
  ++built_;
  return Status::ok;
}

void MeshTail::prepare() {
  // The gate's edge runs a -> b; the edge before it x -> a, after it b -> y.
  x_ = border_reach(prev_[gate_], true);
  y_ = border_reach(next_[gate_], false);
  constexpr uint32_t kTop = TailContexts::kFanClasses - 1;
  const uint32_t fa = m_->pos_[3 * m_->corner_vertex(MeshState::next(corner_[gate_]))];
  const uint32_t fb = m_->pos_[3 * m_->corner_vertex(MeshState::prev(corner_[gate_]))];
  fan_x_ = fa < kTop ? fa : kTop;
  fan_y_ = fb < kTop ? fb : kTop;
}

bool MeshTail::push(uint32_t e) {
  if (depth_ >= m_->cap_v_) return false;
  m_->vertex_corner_.set(depth_++, e);
  return true;
}

bool MeshTail::pop(uint32_t* e) {
  if (depth_ == 0) return false;
  *e = m_->vertex_corner_.get(--depth_);
  return true;
}

Status MeshTail::seed(const bool dummy[3]) {
  if (!needs_seed() || built_ >= total()) return Status::malformed;
  uint32_t v[3], t = 0;
  for (int k = 0; k < 3; ++k) {
    const Status s = new_vertex(dummy[k], &v[k]);
    if (s != Status::ok) return s;
  }
  const Status s = new_triangle(v[0], v[1], v[2], &t);
  if (s != Status::ok) return s;
  // The loop v0 -> v1 -> v2: the edges facing corners 2, 0, 1.
  const uint32_t e2 = new_edge(3 * t + 2), e0 = new_edge(3 * t), e1 = new_edge(3 * t + 1);
  if (e2 == kMeshNone || e0 == kMeshNone || e1 == kMeshNone) return Status::malformed;
  join(e2, e0);
  join(e0, e1);
  join(e1, e2);
  gate_ = e0;
  prepare();
  return Status::ok;
}

Status MeshTail::attach(TailSymbol sym, bool dummy, bool backward, uint32_t offset, uint32_t depth) {
  if (needs_seed() || built_ >= total()) return Status::malformed;
  const uint32_t g = gate_, ex = prev_[g], ey = next_[g];
  const uint32_t a = m_->corner_vertex(MeshState::next(corner_[g]));  // the gate runs a -> b
  const uint32_t b = m_->corner_vertex(MeshState::prev(corner_[g]));
  if (ex == g || ey == g || ex == ey) return Status::malformed;  // every loop has three edges or more
  const bool three = next_[ey] == ex;
  uint32_t tip = kMeshNone, ew = kMeshNone;  // S: the border edge that reaches the tip
  Status s = Status::ok;
  switch (sym) {
    case TailSymbol::C: s = new_vertex(dummy, &tip); break;
    case TailSymbol::L:
    case TailSymbol::R:
      if (three) return Status::malformed;  // a border of three closes (E)
      tip = sym == TailSymbol::L ? x_ : y_;
      break;
    case TailSymbol::E:
      if (!three) return Status::malformed;
      tip = x_;
      break;
    case TailSymbol::S: {
      if (offset < 2 || offset >= live_) return Status::malformed;
      // The walk must stay between the gate's neighbours on this loop.
      const uint32_t stop = backward ? ey : ex;
      ew = border_first(backward);
      for (uint32_t i = 1; i < offset; ++i) {
        ew = border_next(ew, backward);
        if (ew == stop) return Status::malformed;
      }
      if (backward ? prev_[ew] == ey : next_[ew] == ex) return Status::malformed;
      tip = border_reach(ew, backward);
      if (tip == a || tip == b || tip == x_ || tip == y_) return Status::malformed;
      break;
    }
    case TailSymbol::M: {
      if (depth >= depth_ || offset < 1 || offset > live_) return Status::malformed;
      ew = waiting_edge(depth);
      for (uint32_t i = 1; i < offset; ++i) ew = next_[ew];
      if (ew == g || ew == ex || ew == ey) return Status::malformed;  // on the current loop after all
      tip = border_reach(ew, false);
      if (tip == a || tip == b) return Status::malformed;
      break;
    }
  }
  if (s != Status::ok) return s;
  // The new triangle (tip, b, a) shares the gate; its corner c faces it.
  uint32_t t = 0;
  if ((s = new_triangle(tip, b, a, &t)) != Status::ok) return s;
  const uint32_t c = 3 * t;
  m_->link(static_cast<int32_t>(c), static_cast<int32_t>(corner_[g]));
  const uint32_t before = MeshState::next(c);  // its edge a -> tip
  const uint32_t after = MeshState::prev(c);   // its edge tip -> b
  uint32_t next_gate = kMeshNone;
  switch (sym) {
    case TailSymbol::C: {
      // ... x -> a -> tip -> b -> y ...: the gate becomes a -> tip, a new edge tip -> b.
      const uint32_t eb = new_edge(after);
      if (eb == kMeshNone) return Status::malformed;
      corner_[g] = before;
      join(g, eb);
      join(eb, ey);
      next_gate = eb;
      break;
    }
    case TailSymbol::L:
      // x -> a glues to a -> x: ... -> x -> b -> y ...
      m_->link(static_cast<int32_t>(before), static_cast<int32_t>(corner_[ex]));
      join(prev_[ex], g);
      free_edge(ex);
      corner_[g] = after;
      next_gate = g;
      break;
    case TailSymbol::R:
      // b -> y glues to y -> b: ... x -> a -> y -> ...
      m_->link(static_cast<int32_t>(after), static_cast<int32_t>(corner_[ey]));
      join(g, next_[ey]);
      free_edge(ey);
      corner_[g] = before;
      next_gate = g;
      break;
    case TailSymbol::E:
      m_->link(static_cast<int32_t>(before), static_cast<int32_t>(corner_[ex]));
      m_->link(static_cast<int32_t>(after), static_cast<int32_t>(corner_[ey]));
      free_edge(ex);
      free_edge(ey);
      free_edge(g);
      if (!pop(&next_gate)) next_gate = kMeshNone;
      break;
    case TailSymbol::S: {
      // The loop splits at the tip: (tip -> b -> y ... -> tip) goes on,
      // (a -> tip -> ... -> x -> a) waits on the stack.
      const uint32_t ea = new_edge(before);
      if (ea == kMeshNone) return Status::malformed;
      const uint32_t in = backward ? prev_[ew] : ew;    // ... -> tip
      const uint32_t out = backward ? ew : next_[ew];   // tip -> ...
      corner_[g] = after;
      join(in, g);   // ... -> tip -> b -> y ...
      join(ex, ea);  // ... x -> a -> tip
      join(ea, out);
      if (!push(ea)) return Status::malformed;
      next_gate = g;
      break;
    }
    case TailSymbol::M: {
      // The waiting loop joins this one at the tip:
      // ... x -> a -> tip -> (around the waiting loop) -> tip -> b -> y ...
      const uint32_t ea = new_edge(before);
      if (ea == kMeshNone) return Status::malformed;
      const uint32_t out = next_[ew];
      corner_[g] = after;
      join(ex, ea);
      join(ea, out);
      join(ew, g);
      // Its stack entry goes.
      for (uint32_t i = depth_ - 1 - depth; i + 1 < depth_; ++i)
        m_->vertex_corner_.set(i, m_->vertex_corner_.get(i + 1));
      --depth_;
      next_gate = g;
      break;
    }
  }
  gate_ = next_gate;
  if (gate_ == kMeshNone) return depth_ == 0 && live_ == 0 ? Status::ok : Status::malformed;
  prepare();
  return Status::ok;
}

Status MeshTail::finish() {
  if (built_ != total() || gate_ != kMeshNone || depth_ != 0 || live_ != 0 || real_v_ != n_.vertices ||
      dummy_v_ != n_.dummy_vertices || real_t_ != n_.triangles || dummy_t_ != n_.dummy_triangles)
    return Status::malformed;
  MeshState& m = *m_;
  const uint32_t corners = 3 * total(), real = 3 * n_.triangles;
  for (uint32_t c = 0; c < corners; ++c)
    if (m.opposite(c) < 0) return Status::malformed;  // the traversal left an edge open
  for (uint32_t c = 0; c < real; ++c)
    if (static_cast<uint32_t>(m.opposite(c)) >= real) m.set_opp(c, -1);  // across a hole
  m.nv_ = n_.vertices;
  m.nt_ = n_.triangles;
  for (uint32_t v = 0; v < n_.vertices; ++v) {
    m.vertex_corner_.set(v, kMeshNone);
    m.pos_[3 * v] = m.pos_[3 * v + 1] = m.pos_[3 * v + 2] = 0;
  }
  for (uint32_t c = 0; c < real; ++c) {
    const uint32_t v = m.corner_vertex(c);
    if (v >= n_.vertices) return Status::malformed;
    if (m.vertex_corner_.get(v) == kMeshNone) m.vertex_corner_.set(v, c);
  }
  for (uint32_t v = 0; v < n_.vertices; ++v) {
    const uint32_t c = m.vertex_corner_.get(v);
    if (c == kMeshNone) return Status::malformed;  // a vertex only dummy triangles use
    m.fix_vertex_corner(v, c);
  }
  return Status::ok;
}

namespace {

int32_t div_round(int64_t a, int64_t n) { return static_cast<int32_t>(a >= 0 ? (a + n / 2) / n : -((-a + n / 2) / n)); }

}  // namespace

uint32_t mesh_tail_log_class(int64_t x) {
  uint32_t c = 0;
  while (c < TailContexts::kGeoScales - 1 && x >= (int64_t{2} << c)) ++c;
  return c;
}

Status mesh_tail_predict(MeshState& m, uint32_t v, int32_t out[3], uint32_t* context) {
  *context = 0;
  if (v == 0) {
    out[0] = out[1] = out[2] = 1 << (m.bits() - 1);
    return Status::ok;
  }
  Ring r;
  const Status s = m.ring(v, &r, 0);
  if (s != Status::ok) return s;
  int64_t par[3] = {0, 0, 0}, nb[3] = {0, 0, 0};
  int32_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  int32_t edge = 0;
  uint32_t np = 0, nn = 0;
  const uint16_t* pos = m.positions();
  for (uint32_t j = 0; j < r.degree; ++j) {
    const uint32_t w = r.vertex[j];
    if (w < v) {
      for (int k = 0; k < 3; ++k) nb[k] += pos[3 * w + k];
      ++nn;
    }
  }
  for (uint32_t j = 0; j < r.faces(); ++j) {
    const uint32_t p = r.vertex[j], q = r.vertex[(j + 1) % r.degree];
    if (p >= v || q >= v) continue;
    const int32_t o = m.opposite(r.corner[j]);
    if (o < 0) continue;
    const uint32_t d = m.corner_vertex(static_cast<uint32_t>(o));
    if (d >= v) continue;
    for (int k = 0; k < 3; ++k) {
      const int32_t x = int32_t{pos[3 * p + k]} + pos[3 * q + k] - pos[3 * d + k];
      par[k] += x;
      if (np == 0 || x < lo[k]) lo[k] = x;
      if (np == 0 || x > hi[k]) hi[k] = x;
      const int32_t e = int32_t{pos[3 * p + k]} - pos[3 * q + k];
      if ((e < 0 ? -e : e) > edge) edge = e < 0 ? -e : e;
    }
    ++np;
  }
  const int32_t top = (1 << m.bits()) - 1;
  for (int k = 0; k < 3; ++k) {
    int32_t x;
    if (np > 0) x = div_round(par[k], np);
    else if (nn > 0) x = div_round(nb[k], nn);
    else x = pos[3 * (v - 1) + k];
    out[k] = x < 0 ? 0 : (x > top ? top : x);
  }
  // Context: how far apart the parallelograms land (two or more), else
  // the length of the edge a single one is built across.
  if (np >= 2) {
    int32_t spread = 0;
    for (int k = 0; k < 3; ++k) spread = hi[k] - lo[k] > spread ? hi[k] - lo[k] : spread;
    *context = 1 + TailContexts::kGeoScales + mesh_tail_log_class(spread);
  } else if (np == 1) {
    *context = 1 + mesh_tail_log_class(edge);
  }
  return Status::ok;
}

}  // namespace vds
