// The plane-induced homography between two cameras and its local scale factor
// (texture quality factor), in fixed point: Cohen-Or, Mann, Fleishman, "Deep
// compression for streaming texture intensive animations", sec. 4, eqs. 5-9.
//
// Matrices are carried in block floating point: 64-bit entries with a shared
// power-of-two exponent, renormalised after each product so that the largest
// entry lies in [2^29, 2^30). A product of two such matrices sums three
// products below 2^60, so no intermediate overflows, and each step keeps 29
// significant bits of the largest entry. The final homography is scale-free,
// so its exponent is dropped.
#include "vds/homography.h"

#include "vds/render_camera.h"

namespace vds {

namespace {

constexpr int kNormBits = 30;  // entries normalised below 2^30


// v * 2^-s for s >= 0 rounded to nearest, v * 2^|s| for s < 0 (caller keeps
// the result in range).
int64_t shift_round(int64_t v, int s) {
  if (s <= 0) return static_cast<int64_t>(static_cast<uint64_t>(v) << (-s));
  if (s >= 63) return 0;
  return shr_round(v, s);
}

using BMat = HomographyCameras::BlockMatrix;
using BVec = HomographyCameras::BlockVector;

// Renormalises so that max |entry| is in [2^29, 2^30) (or all zero).
void normalise(BMat& a) {
  uint64_t mx = 0;
  for (auto& row : a.m)
    for (int64_t x : row) {
      const uint64_t ax = abs64(x);
      if (ax > mx) mx = ax;
    }
  if (mx == 0) return;
  const int s = bitlen64(mx) - kNormBits;
  for (auto& row : a.m)
    for (int64_t& x : row) x = shift_round(x, s);
  a.e += s;
  // Rounding up may have reached 2^30; one more halving keeps the bound.
  for (auto& row : a.m)
    for (int64_t x : row)
      if (abs64(x) >= (uint64_t{1} << kNormBits)) {
        for (auto& r2 : a.m)
          for (int64_t& y : r2) y = shift_round(y, 1);
        ++a.e;
        return;
      }
}

void normalise(BVec& a) {
  uint64_t mx = 0;
  for (int64_t x : a.v) {
    const uint64_t ax = abs64(x);
    if (ax > mx) mx = ax;
  }
  if (mx == 0) return;
  const int s = bitlen64(mx) - kNormBits + 1;  // below 2^29: room for rounding
  if (mx < (uint64_t{1} << 31)) {
    // Entries of 32 bits (a difference of two Q16.16 points): the same
    // shifts in 32-bit arithmetic (s <= 2; every result below 2^29).
    for (int64_t& x : a.v) {
      const int32_t v = static_cast<int32_t>(x);
      x = s <= 0 ? static_cast<int32_t>(static_cast<uint32_t>(v) << -s) : shr_round(v, s);
    }
  } else {
    for (int64_t& x : a.v) x = shift_round(x, s);
  }
  a.e += s;
}

BMat mul(const BMat& a, const BMat& b) {
  BMat r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      int64_t acc = 0;
      for (int k = 0; k < 3; ++k) acc += a.m[i][k] * b.m[k][j];  // 3 x 2^60: no overflow
      r.m[i][j] = acc;
    }
  r.e = a.e + b.e;
  normalise(r);
  return r;
}

// The conditioning S = diag(256, 256, 1) of vds/homography.h is folded into
// the intrinsics: S^-1 K_to on the left and K_from^-1 S on the right.
BMat intrinsics_scaled(const Camera& c) {
  // S^-1 K = [[fx, 0, cx], [0, fy, cy], [0, 0, 256]] / 256, from Q16.16.
  BMat k{{{c.fx.raw(), 0, c.cx.raw()}, {0, c.fy.raw(), c.cy.raw()}, {0, 0, int64_t{1} << 24}}, -24};
  normalise(k);
  return k;
}

BMat inverse_intrinsics_scaled(const Camera& c) {
  // fx fy K^-1 S = [[256 fy, 0, -cx fy], [0, 256 fx, -cy fx], [0, 0, fx fy]]
  // (scale-free), with 32 fraction bits: every entry an exact 64-bit product.
  const int64_t fx = c.fx.raw(), fy = c.fy.raw();
  BMat k{{{fy << 24, 0, -int64_t{c.cx.raw()} * fy}, {0, fx << 24, -int64_t{c.cy.raw()} * fx}, {0, 0, fx * fy}}, -32};
  normalise(k);
  return k;
}

BMat rotation(const Camera& c, bool transpose) {
  BMat r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = transpose ? c.rotation.m[j][i].raw() : c.rotation.m[i][j].raw();
  r.e = -30;
  normalise(r);
  return r;
}

BVec vec_diff(const Vec3<Q16_16>& a, const Vec3<Q16_16>& b) {
  BVec d{{int64_t{a.x.raw()} - b.x.raw(), int64_t{a.y.raw()} - b.y.raw(), int64_t{a.z.raw()} - b.z.raw()}, -16};
  normalise(d);
  return d;
}

// 65536 (a x' + b y' + c) for a row (a, b, c) at the scaled point
// (x', y') = (x, y) / 256, from Q24.8 pixels: a x_q8 + b y_q8 + 65536 c.
// Exact for the normalised matrices made here (|entry| < 2^30, |coordinate|
// < 2^31: below 2^62.6); wraps (defined, meaningless) for wilder matrices.
int64_t eval_row_q8(const int32_t row[3], int32_t x_q8, int32_t y_q8) {
  return mac64(mac64(mul32x32_64(row[0], x_q8), row[1], y_q8), row[2], 65536);
}

// round-toward-zero of num * 2^frac / den, saturated to int32; den != 0.
int32_t ratio_sat(int64_t num, int64_t den, int frac) {
  if (den < 0) {
    den = -den;  // |den| < 2^63 by construction of every caller
    num = -num;
  }
  // Bring den below 2^31 (the quotient keeps 31 significant bits of den).
  const int sd = bitlen64(static_cast<uint64_t>(den)) - 31;
  if (sd > 0) {
    den >>= sd;
    frac -= sd;
  }
  if (den == 0) return 0;
  const bool neg = num < 0;
  uint64_t n = abs64(num);
  if (frac >= 0) {
    // n * 2^frac must stay below 2^63; beyond, the quotient is >= 2^32 anyway.
    if (frac >= 63 || (n != 0 && bitlen64(n) + frac > 62)) return neg ? INT32_MIN : INT32_MAX;
    n <<= frac;
  } else {
    n = (-frac >= 64) ? 0 : (n >> (-frac));
  }
  const uint64_t q = n / static_cast<uint64_t>(den);
  if (q > static_cast<uint64_t>(INT32_MAX)) return neg ? INT32_MIN : INT32_MAX;
  const int32_t r = static_cast<int32_t>(q);
  return neg ? -r : r;
}

// m v, or v^T m (transposed), renormalised. Entries of both below 2^30:
// 32 x 32-bit products.
BVec mul_vec(const BMat& m, const BVec& v, bool transposed) {
  BVec r;
  for (int i = 0; i < 3; ++i) {
    int64_t acc = 0;
    for (int k = 0; k < 3; ++k) {
      acc += mul32x32_64(static_cast<int32_t>(transposed ? m.m[k][i] : m.m[i][k]), static_cast<int32_t>(v.v[k]));  // < 3 x 2^60
    }
    r.v[i] = acc;
  }
  r.e = m.e + v.e;
  normalise(r);
  return r;
}

}  // namespace

Status homography_cameras(const Camera& from, const Camera& to, HomographyCameras* out) {
  if (!out) return Status::invalid_argument;
  if (validate_camera(from) != Status::ok || validate_camera(to) != Status::ok) return Status::invalid_argument;
  const BMat left = mul(intrinsics_scaled(to), rotation(to, false));
  out->r = mul(rotation(from, true), inverse_intrinsics_scaled(from));
  out->lr = mul(left, out->r);
  const BVec c = vec_diff(from.position, to.position);
  out->lc = c.v[0] == 0 && c.v[1] == 0 && c.v[2] == 0 ? BVec{{0, 0, 0}, 0} : mul_vec(left, c, false);
  out->from_position = from.position;
  return Status::ok;
}

Status plane_homography(const Camera& from, const Camera& to, const Vec3<Q16_16> plane[3], Homography* out) {
  HomographyCameras cams;
  const Status s = homography_cameras(from, to, &cams);
  return s != Status::ok ? s : plane_homography(cams, plane, out);
}

Status plane_homography(const HomographyCameras& cams, const Vec3<Q16_16> plane[3], Homography* out) {
  if (!out || !plane) return Status::invalid_argument;

  // Plane normal n = (P1 - P0) x (P2 - P0); its scale cancels in the
  // homography, so each edge is normalised on its own.
  const BVec e1 = vec_diff(plane[1], plane[0]);
  const BVec e2 = vec_diff(plane[2], plane[0]);
  // Entries below 2^30 after normalise: 32 x 32-bit products.
  const auto m = [](int64_t a, int64_t b) { return mul32x32_64(static_cast<int32_t>(a), static_cast<int32_t>(b)); };
  BVec n{{m(e1.v[1], e2.v[2]) - m(e1.v[2], e2.v[1]), m(e1.v[2], e2.v[0]) - m(e1.v[0], e2.v[2]),
          m(e1.v[0], e2.v[1]) - m(e1.v[1], e2.v[0])},
         0};
  normalise(n);
  if (n.v[0] == 0 && n.v[1] == 0 && n.v[2] == 0) return Status::invalid_argument;

  // d = n . (P0 - C_from): distance of the plane from the `from` centre
  // (times |n|). Zero means the plane contains that centre. Kept below
  // 2^30 with its exponent.
  const BVec p = vec_diff(plane[0], cams.from_position);
  int64_t delta = m(n.v[0], p.v[0]) + m(n.v[1], p.v[1]) + m(n.v[2], p.v[2]);  // < 3 * 2^58
  if (delta == 0) return Status::invalid_argument;
  int delta_e = n.e + p.e;
  const int ds = bitlen64(abs64(delta)) - kNormBits;
  if (ds > 0) {
    delta = shift_round(delta, ds);
    delta_e += ds;
  }

  // H = d (L R) + (L c)(n^T R): every product of two entries below 2^30.
  const BVec b = mul_vec(cams.r, n, true);
  const bool rotation_only = cams.lc.v[0] == 0 && cams.lc.v[1] == 0 && cams.lc.v[2] == 0;
  const int e_d = delta_e + cams.lr.e, e_c = cams.lc.e + b.e;
  const int e = (rotation_only || e_d > e_c) ? e_d : e_c;
  BMat h;
  h.e = e;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      int64_t v = shift_round(mul32x32_64(static_cast<int32_t>(delta), static_cast<int32_t>(cams.lr.m[i][j])), e - e_d);
      if (!rotation_only) {
        v += shift_round(mul32x32_64(static_cast<int32_t>(cams.lc.v[i]), static_cast<int32_t>(b.v[j])), e - e_c);
      }
      h.m[i][j] = v;
    }
  normalise(h);

  Homography r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = static_cast<int32_t>(h.m[i][j]);  // < 2^30 after normalise

  // Sign: along the ray d of a `from` pixel the result is (n . d) times the
  // point in `to` camera space, and n . d has the sign of delta for points in
  // front of `from`. So with delta > 0, W > 0 exactly where `to` sees the point.
  if (delta < 0) {
    for (auto& row : r.m)
      for (int32_t& v : row) v = -v;
  }
  *out = r;
  return Status::ok;
}

bool homography_apply(const Homography& h, int32_t x_q8, int32_t y_q8, int32_t* out_x_q8, int32_t* out_y_q8) {
  // Each row value is 256 (a x + b y + c) with |entries| < 2^31: below 2^62.6.
  const int64_t X = eval_row_q8(h.m[0], x_q8, y_q8);
  const int64_t Y = eval_row_q8(h.m[1], x_q8, y_q8);
  const int64_t W = eval_row_q8(h.m[2], x_q8, y_q8);
  if (W <= 0) return false;
  // Pixels = 256 X / W, in Q24.8: X / W * 2^16.
  const int32_t ox = ratio_sat(X, W, 16);
  const int32_t oy = ratio_sat(Y, W, 16);
  if (ox == INT32_MAX || ox == INT32_MIN || oy == INT32_MAX || oy == INT32_MIN) return false;
  *out_x_q8 = ox;
  *out_y_q8 = oy;
  return true;
}

Q16_16 homography_scale(const Homography& h, int32_t x_q8, int32_t y_q8) {
  // (X, Y, W) at the point (65536 times the values of the scaled map), then
  // brought below 2^30 together: the ratios x1 = X/W, y1 = Y/W are unchanged.
  // The conditioning scales source and target alike, so the Jacobian of the
  // scaled map equals that of the pixel map.
  int64_t X = eval_row_q8(h.m[0], x_q8, y_q8);
  int64_t Y = eval_row_q8(h.m[1], x_q8, y_q8);
  int64_t W = eval_row_q8(h.m[2], x_q8, y_q8);
  if (W == 0) return Q16_16::max();
  uint64_t mx = abs64(X);
  if (abs64(Y) > mx) mx = abs64(Y);
  if (abs64(W) > mx) mx = abs64(W);
  int s = bitlen64(mx) - kNormBits;
  if (s < 0) s = 0;
  X = shr_round(X, s);
  Y = shr_round(Y, s);
  W = shr_round(W, s);
  if (W == 0) return Q16_16::max();
  // Eq. 9 over a common denominator: J11 = (a W - X g) / W^2 (true W =
  // W 2^s / 65536, true X likewise), so J11 = (a W - X g) 2^(16 - s) / W^2; in
  // Q16.16 that is a shift of 32 - s.
  const int64_t a = h.m[0][0], b = h.m[0][1], d = h.m[1][0], e = h.m[1][1];
  const int64_t g = h.m[2][0], hh = h.m[2][1];
  const int64_t w2 = W * W;  // < 2^60
  const int frac = 32 - s;
  constexpr int32_t kJLimit = 2047 << 16;  // entries saturate at +-2047
  auto entry = [&](int64_t num) {
    const int32_t v = ratio_sat(num, w2, frac);
    return v > kJLimit ? kJLimit : v < -kJLimit ? -kJLimit : v;
  };
  const int64_t j11 = entry(a * W - X * g);  // each product < 2^60
  const int64_t j12 = entry(b * W - X * hh);
  const int64_t j21 = entry(d * W - Y * g);
  const int64_t j22 = entry(e * W - Y * hh);

  // Eq. 5: lambda_max = S + sqrt(S^2 - det^2), S = (sum of squares) / 2. With
  //   2 (S - det) = (j11 - j22)^2 + (j12 + j21)^2,
  //   2 (S + det) = (j11 + j22)^2 + (j12 - j21)^2,
  // both sums of squares (no cancellation), S^2 - det^2 = (S - det)(S + det)
  // and lambda = (p + q) / 4 + sqrt(p) sqrt(q) / 2 with p, q the two sums.
  // Entries are Q16.16 below 2^27, so p, q < 2^57 (Q32).
  const uint64_t p = static_cast<uint64_t>((j11 - j22) * (j11 - j22) + (j12 + j21) * (j12 + j21));
  const uint64_t q = static_cast<uint64_t>((j11 + j22) * (j11 + j22) + (j12 - j21) * (j12 - j21));
  const uint64_t sp = isqrt64_round(p);  // Q16, < 2^29
  const uint64_t sq = isqrt64_round(q);
  const uint64_t lambda = ((p + q) >> 2) + ((sp * sq) >> 1);  // Q32, < 2^58
  const uint64_t norm = isqrt64_round(lambda);             // Q16
  return norm > static_cast<uint64_t>(INT32_MAX) ? Q16_16::max() : Q16_16::from_raw(static_cast<int32_t>(norm));
}

Status texture_quality(const Camera& screen, const Camera& view, const Vec3<Q16_16>* poly, size_t n, Q16_16* quality) {
  if (!poly || n < 3 || !quality) return Status::invalid_argument;
  Homography vs;
  const Status st = plane_homography(view, screen, poly, &vs);
  if (st != Status::ok) return st;
  Q16_16 worst = Q16_16::from_raw(0);
  for (size_t i = 0; i < n; ++i) {
    int32_t x, y;
    if (!camera_project(view, camera_transform(view, poly[i]), &x, &y)) {
      worst = Q16_16::max();
      break;
    }
    const Q16_16 s = homography_scale(vs, x, y);
    if (s > worst) worst = s;
  }
  *quality = worst;
  return Status::ok;
}

}  // namespace vds
