// Tests of vds/fixed.h against independent references: double / long double
// for approximations and for values double holds exactly, 128-bit integer
// arithmetic for exact results on 64-bit values. Each test asserts the error
// bound the header states, exhaustively where the domain has <= 2^24 inputs
// and by dense sampling plus every edge value otherwise.
#include "vds/fixed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace vds {
namespace {

using i128 = __int128;
using u128 = unsigned __int128;

// ---------------------------------------------------------------------------
// Input sets
// ---------------------------------------------------------------------------
std::vector<int32_t> edge_s32() {
  std::vector<int32_t> v = {0, 1, -1, 2, -2, 3, -3, INT32_MIN, INT32_MIN + 1, INT32_MIN + 2, INT32_MAX, INT32_MAX - 1};
  for (int k = 2; k <= 30; ++k) {
    const int32_t p = int32_t{1} << k;
    for (const int32_t e : {p - 1, p, p + 1}) {
      v.push_back(e);
      v.push_back(-e);
    }
  }
  return v;
}

std::vector<uint32_t> edge_u32() {
  std::vector<uint32_t> v = {0, 1, 2, 3, UINT32_MAX, UINT32_MAX - 1};
  for (int k = 2; k <= 31; ++k) {
    const uint32_t p = uint32_t{1} << k;
    v.push_back(p - 1);
    v.push_back(p);
    v.push_back(p + 1);
  }
  return v;
}

std::vector<int64_t> edge_s64() {
  std::vector<int64_t> v = {0, 1, -1, INT64_MIN, INT64_MIN + 1, INT64_MAX, INT64_MAX - 1};
  for (int k = 1; k <= 62; ++k) {
    const int64_t p = int64_t{1} << k;
    for (const int64_t e : {p - 1, p, p + 1}) {
      v.push_back(e);
      v.push_back(-e);
    }
  }
  return v;
}

// Mostly small magnitudes, sometimes anything: random shifts of random words.
int32_t rand_s32(std::mt19937_64& rng) { return static_cast<int32_t>(rng()) >> (rng() % 32); }
uint32_t rand_u32(std::mt19937_64& rng) { return static_cast<uint32_t>(rng()) >> (rng() % 32); }
int64_t rand_s64(std::mt19937_64& rng) { return static_cast<int64_t>(rng()) >> (rng() % 64); }

// ---------------------------------------------------------------------------
// Exact references
// ---------------------------------------------------------------------------
enum class Mode { floor, ceil, trunc, round };
constexpr Mode kModes[] = {Mode::floor, Mode::ceil, Mode::trunc, Mode::round};

// floor / ceil / trunc / round-half-up of n / d, d > 0, in 128-bit integers.
i128 div_ref(i128 n, i128 d, Mode m) {
  i128 q = n / d;  // truncates
  const i128 r = n % d;
  switch (m) {
    case Mode::trunc: return q;
    case Mode::floor: return (r != 0 && n < 0) ? q - 1 : q;
    case Mode::ceil: return (r != 0 && n > 0) ? q + 1 : q;
    case Mode::round: return div_ref(2 * n + d, 2 * d, Mode::floor);
  }
  return q;
}

// v * 2^d (d >= 0) or v / 2^-d rounded by m, in 128-bit integers.
i128 rescale_ref(i128 v, int d, Mode m) {
  return d >= 0 ? v * (i128{1} << d) : div_ref(v, i128{1} << -d, m);
}

template <typename Rep>
int64_t wrap_ref(i128 v) {
  return static_cast<Rep>(static_cast<uint64_t>(static_cast<u128>(v)));  // low bits, sign-extended
}
template <typename Rep>
int64_t sat_ref(i128 v) {
  constexpr i128 hi = std::numeric_limits<Rep>::max(), lo = std::numeric_limits<Rep>::min();
  return static_cast<int64_t>(v > hi ? hi : v < lo ? lo : v);
}

// The same roundings in double, for values double holds exactly.
double round_double(double x, Mode m) {
  switch (m) {
    case Mode::floor: return std::floor(x);
    case Mode::ceil: return std::ceil(x);
    case Mode::trunc: return std::trunc(x);
    case Mode::round: return std::floor(x + 0.5);
  }
  return x;
}

// ---------------------------------------------------------------------------
// Integer helpers
// ---------------------------------------------------------------------------
TEST(FixedIntegerTest, ClzAndIlog2) {
  EXPECT_EQ(clz32(0), 32);
  EXPECT_EQ(clz64(0), 64);
  EXPECT_EQ(ilog2(0), -1);
  EXPECT_EQ(ilog2_64(0), -1);
  for (int k = 0; k < 32; ++k) {
    const uint32_t p = uint32_t{1} << k;
    EXPECT_EQ(clz32(p), 31 - k);
    EXPECT_EQ(clz32(p | (p - 1)), 31 - k);
    EXPECT_EQ(ilog2(p), k);
    if (k > 0) EXPECT_EQ(ilog2(p - 1), k - 1);
    if (k < 31) EXPECT_EQ(ilog2(p + 1), k + (p == 1));
  }
  for (int k = 0; k < 64; ++k) {
    const uint64_t p = uint64_t{1} << k;
    EXPECT_EQ(clz64(p), 63 - k);
    EXPECT_EQ(clz64(p | (p - 1)), 63 - k);
    EXPECT_EQ(ilog2_64(p), k);
  }
  // Against the double logarithm on random words (exact for these sizes).
  std::mt19937_64 rng(11);
  for (int i = 0; i < 100000; ++i) {
    const uint32_t x = rand_u32(rng) | 1;
    EXPECT_EQ(ilog2(x), static_cast<int>(std::floor(std::log2(static_cast<double>(x)) + 1e-12))) << x;
    const uint64_t y = rng() >> (rng() % 64);
    if (y) EXPECT_EQ(clz64(y), 63 - static_cast<int>(std::floor(std::log2(static_cast<long double>(y)) + 1e-15L)));
  }
}

TEST(FixedIntegerTest, ProductsMatchExact128Bit) {
  std::vector<int32_t> s = edge_s32();
  std::vector<uint32_t> u = edge_u32();
  std::mt19937_64 rng(12);
  for (int i = 0; i < 2000; ++i) {
    s.push_back(static_cast<int32_t>(rng()));
    u.push_back(static_cast<uint32_t>(rng()));
  }
  for (const int32_t a : s) {
    for (size_t j = 0; j < s.size(); j += 7) {
      const int32_t b = s[j];
      const i128 p = i128{a} * b;
      ASSERT_EQ(mul32x32_64(a, b), static_cast<int64_t>(p));
      ASSERT_EQ(mulhi(a, b), static_cast<int32_t>(div_ref(p, i128{1} << 32, Mode::floor)));
      ASSERT_EQ(mulhi_round(a, b), static_cast<int32_t>(div_ref(p, i128{1} << 32, Mode::round)));
      const int64_t acc = static_cast<int64_t>(rng());
      ASSERT_EQ(mac64(acc, a, b), static_cast<int64_t>(static_cast<uint64_t>(acc + p)));  // modulo 2^64
    }
  }
  for (const uint32_t a : u) {
    for (size_t j = 0; j < u.size(); j += 7) {
      const uint32_t b = u[j];
      const u128 p = u128{a} * b;
      ASSERT_EQ(umul32x32_64(a, b), static_cast<uint64_t>(p));
      ASSERT_EQ(umulhi(a, b), static_cast<uint32_t>(p >> 32));
    }
  }
  // Ties of the rounded high word go up: +-1/2 in units of 2^32.
  EXPECT_EQ(mulhi_round(1 << 16, 1 << 15), 1);   // +0.5 -> 1
  EXPECT_EQ(mulhi_round(-(1 << 16), 1 << 15), 0);  // -0.5 -> 0
  EXPECT_EQ(mulhi_round(3 << 15, 1 << 16), 2);   // +1.5 -> 2
  EXPECT_EQ(mulhi_round(-(3 << 15), 1 << 16), -1);  // -1.5 -> -1
  EXPECT_EQ(mulhi_round(INT32_MIN, INT32_MIN), 1 << 30);
}

TEST(FixedIntegerTest, SaturatingClamps) {
  for (int64_t v = -(int64_t{1} << 17); v <= (int64_t{1} << 17); ++v) {
    const int32_t v32 = static_cast<int32_t>(v);
    ASSERT_EQ(sat_s16(v32), std::clamp<int64_t>(v, INT16_MIN, INT16_MAX));
    ASSERT_EQ(sat_u8(v32), std::clamp<int64_t>(v, 0, 255));
    ASSERT_EQ(sat_signed_bits<9>(v32), std::clamp<int64_t>(v, -256, 255));
    ASSERT_EQ(sat_signed_bits<1>(v32), std::clamp<int64_t>(v, -1, 0));
    ASSERT_EQ(sat_unsigned_bits<10>(v32), std::clamp<int64_t>(v, 0, 1023));
    ASSERT_EQ(sat_unsigned_bits<0>(v32), 0);
  }
  for (const int32_t v : edge_s32()) {
    EXPECT_EQ(sat_s16(v), std::clamp<int32_t>(v, INT16_MIN, INT16_MAX));
    EXPECT_EQ(sat_signed_bits<32>(v), v);
    EXPECT_EQ(sat_signed_bits<16>(v), std::clamp<int32_t>(v, INT16_MIN, INT16_MAX));
    EXPECT_EQ(sat_unsigned_bits<31>(v), std::max(v, 0));
    EXPECT_EQ(clamp_s32(v, -5, 7), std::clamp(v, -5, 7));
  }
  for (const int64_t v : edge_s64()) EXPECT_EQ(sat_s32(v), std::clamp<int64_t>(v, INT32_MIN, INT32_MAX));
}

TEST(FixedIntegerTest, RoundingShifts) {
  // Exhaustive over a window that holds every tie, in double (exact here).
  for (int32_t v = -5000; v <= 5000; ++v) {
    for (int s = 0; s <= 14; ++s) {
      const double x = std::ldexp(static_cast<double>(v), -s);
      ASSERT_EQ(shr_floor(v, s), round_double(x, Mode::floor));
      ASSERT_EQ(shr_ceil(v, s), round_double(x, Mode::ceil));
      ASSERT_EQ(shr_trunc(v, s), round_double(x, Mode::trunc));
      ASSERT_EQ(shr_round(v, s), round_double(x, Mode::round)) << v << " " << s;
    }
  }
  // Ties: up for _round, whatever the sign.
  EXPECT_EQ(shr_round(1, 1), 1);    // 0.5
  EXPECT_EQ(shr_round(-1, 1), 0);   // -0.5
  EXPECT_EQ(shr_round(3, 1), 2);    // 1.5
  EXPECT_EQ(shr_round(-3, 1), -1);  // -1.5
  EXPECT_EQ(shr_round(-5, 1), -2);  // -2.5
  EXPECT_EQ(shr_trunc(-5, 1), -2);
  EXPECT_EQ(shr_floor(-5, 1), -3);
  EXPECT_EQ(shr_ceil(-5, 1), -2);
  // No overflow at the extremes, every shift, both widths.
  for (const int32_t v : edge_s32()) {
    for (int s = 0; s < 32; ++s) {
      const double x = std::ldexp(static_cast<double>(v), -s);
      for (const Mode m : kModes) {
        const int32_t got = m == Mode::floor ? shr_floor(v, s) : m == Mode::ceil ? shr_ceil(v, s) : m == Mode::trunc ? shr_trunc(v, s) : shr_round(v, s);
        ASSERT_EQ(got, round_double(x, m)) << v << " " << s;
      }
    }
  }
  std::vector<int64_t> v64 = edge_s64();
  std::mt19937_64 rng(13);
  for (int i = 0; i < 20000; ++i) v64.push_back(rand_s64(rng));
  for (const int64_t v : v64) {
    for (int s = 0; s < 64; ++s) {
      const i128 d = i128{1} << s;
      ASSERT_EQ(shr_floor(v, s), static_cast<int64_t>(div_ref(v, d, Mode::floor)));
      ASSERT_EQ(shr_ceil(v, s), static_cast<int64_t>(div_ref(v, d, Mode::ceil)));
      ASSERT_EQ(shr_trunc(v, s), static_cast<int64_t>(div_ref(v, d, Mode::trunc)));
      ASSERT_EQ(shr_round(v, s), static_cast<int64_t>(div_ref(v, d, Mode::round))) << v << " " << s;
    }
  }
}

// ---------------------------------------------------------------------------
// The Fixed type
// ---------------------------------------------------------------------------
template <typename... T>
struct TypeList {};
using AllFormats = TypeList<Q1_15, Q4_12, Q8_8, Q12_4, Q2_30, Q16_16, Q24_8, Q28_4>;

// Every raw value of an int16 format, or edges plus random values of an int32 one.
template <typename Q>
std::vector<int32_t> raw_samples(int random_count) {
  std::vector<int32_t> v;
  if constexpr (sizeof(typename Q::rep) == 2) {
    for (int32_t r = INT16_MIN; r <= INT16_MAX; ++r) v.push_back(r);
  } else {
    v = edge_s32();
    std::mt19937_64 rng(14);
    for (int i = 0; i < random_count; ++i) v.push_back(rand_s32(rng));
  }
  return v;
}

static_assert(Q16_16::from_ratio(13, 10).raw() == 85197);  // 1.3 * 65536 = 85196.8
static_assert(Q16_16::from_ratio(-13, 10).raw() == -85197);
static_assert(Q16_16::from_ratio(1, 131072).raw() == 1);   // exactly 1/2 ulp: ties up
static_assert(Q16_16::from_ratio(-1, 131072).raw() == 0);
static_assert(Q1_15::from_ratio(-1, 1).raw() == INT16_MIN);
static_assert(Q2_30::one().raw() == (1 << 30) && Q8_8::one().raw() == 256);
static_assert(Q16_16::from_int(-3).to_int_floor() == -3);

template <typename Q>
void check_int_conversions() {
  SCOPED_TRACE(Q::kFracBits);
  for (const int32_t r : raw_samples<Q>(200000)) {
    const Q q = Q::from_raw(static_cast<typename Q::rep>(r));
    ASSERT_EQ(q.raw(), r);
    const double x = std::ldexp(static_cast<double>(r), -Q::kFracBits);
    ASSERT_EQ(q.to_int_floor(), round_double(x, Mode::floor));
    ASSERT_EQ(q.to_int_ceil(), round_double(x, Mode::ceil));
    ASSERT_EQ(q.to_int_trunc(), round_double(x, Mode::trunc));
    ASSERT_EQ(q.to_int_round(), round_double(x, Mode::round));
  }
  for (const int32_t i : edge_s32()) {
    const i128 want = i128{i} << Q::kFracBits;
    EXPECT_EQ(Q::from_int(i).raw(), wrap_ref<typename Q::rep>(want)) << i;
    EXPECT_EQ(Q::from_int_sat(i).raw(), sat_ref<typename Q::rep>(want)) << i;
  }
}

TEST(FixedTypeTest, IntConversionsAllFormats) {
  check_int_conversions<Q1_15>();
  check_int_conversions<Q4_12>();
  check_int_conversions<Q8_8>();
  check_int_conversions<Q12_4>();
  check_int_conversions<Q2_30>();
  check_int_conversions<Q16_16>();
  check_int_conversions<Q24_8>();
  check_int_conversions<Q28_4>();
}

template <typename From, typename To>
void check_convert_pair(const std::vector<int32_t>& raws) {
  using Rep = typename To::rep;
  const int d = To::kFracBits - From::kFracBits;
  for (const int32_t r : raws) {
    const From x = From::from_raw(static_cast<typename From::rep>(r));
    // Reference in double: r * 2^d is exact, and so is adding 1/2 to it.
    int64_t want[4];
    for (int m = 0; m < 4; ++m) want[m] = static_cast<int64_t>(round_double(std::ldexp(static_cast<double>(r), d), kModes[m]));
    const int64_t got[8] = {convert_floor<To>(x).raw(),     convert_ceil<To>(x).raw(),     convert_trunc<To>(x).raw(),
                            convert_round<To>(x).raw(),     convert_floor_sat<To>(x).raw(), convert_ceil_sat<To>(x).raw(),
                            convert_trunc_sat<To>(x).raw(), convert_round_sat<To>(x).raw()};
    for (int m = 0; m < 4; ++m) {
      ASSERT_EQ(got[m], wrap_ref<Rep>(want[m])) << "wrap mode " << m << " raw " << r << " " << From::kFracBits << "->" << To::kFracBits;
      ASSERT_EQ(got[4 + m], sat_ref<Rep>(want[m])) << "sat mode " << m << " raw " << r << " " << From::kFracBits << "->" << To::kFracBits;
    }
  }
}
template <typename From, typename... To>
void check_convert_from(TypeList<To...>) {
  const std::vector<int32_t> raws = raw_samples<From>(20000);
  (check_convert_pair<From, To>(raws), ...);
}
template <typename... From>
void check_convert_all(TypeList<From...> all) {
  (check_convert_from<From>(all), ...);
}

TEST(FixedTypeTest, ConversionsAllPairsAllModes) {
  check_convert_all(AllFormats{});
  // Named cases: halves and limits.
  EXPECT_EQ(convert_round<Q8_8>(Q16_16::from_raw(0x80)).raw(), 1);     // 1/2 ulp of Q8_8 -> up
  EXPECT_EQ(convert_round<Q8_8>(Q16_16::from_raw(-0x80)).raw(), 0);    // -1/2 ulp -> up
  EXPECT_EQ(convert_trunc<Q8_8>(Q16_16::from_raw(-0x180)).raw(), -1);  // -1.5 ulp -> -1
  EXPECT_EQ(convert_floor<Q8_8>(Q16_16::from_raw(-0x180)).raw(), -2);
  EXPECT_EQ(convert_ceil<Q8_8>(Q16_16::from_raw(0x101)).raw(), 2);
  EXPECT_EQ(convert_round_sat<Q8_8>(Q16_16::from_int(200)), Q8_8::max());
  EXPECT_EQ(convert_round_sat<Q8_8>(Q16_16::from_int(-200)), Q8_8::min());
  EXPECT_EQ(convert_round<Q8_8>(Q16_16::from_int(200)).raw(), static_cast<int16_t>(200 * 256 - 65536));  // wraps
  EXPECT_EQ(convert_round_sat<Q1_15>(Q2_30::one()), Q1_15::max());
  EXPECT_EQ(convert_round_sat<Q1_15>(Q2_30::from_raw((1 << 30) - (1 << 14))), Q1_15::max());  // rounds to 1.0, clamps
  EXPECT_EQ(convert_round_sat<Q16_16>(Q24_8::max()), Q16_16::max());
}

template <typename Q>
void check_add_sub() {
  using Rep = typename Q::rep;
  std::vector<int32_t> a = raw_samples<Q>(300);
  if constexpr (sizeof(Rep) == 2) {
    std::vector<int32_t> thin;  // every 61st value plus all the ends
    for (size_t i = 0; i < a.size(); ++i) {
      if (i % 61 == 0 || i < 5 || i + 5 >= a.size()) thin.push_back(a[i]);
    }
    a = thin;
  }
  for (const int32_t x : a) {
    for (const int32_t y : a) {
      const Q qx = Q::from_raw(static_cast<Rep>(x)), qy = Q::from_raw(static_cast<Rep>(y));
      ASSERT_EQ((qx + qy).raw(), wrap_ref<Rep>(i128{x} + y));
      ASSERT_EQ((qx - qy).raw(), wrap_ref<Rep>(i128{x} - y));
      ASSERT_EQ(add_sat(qx, qy).raw(), sat_ref<Rep>(i128{x} + y));
      ASSERT_EQ(sub_sat(qx, qy).raw(), sat_ref<Rep>(i128{x} - y));
    }
    const Q qx = Q::from_raw(static_cast<Rep>(x));
    ASSERT_EQ((-qx).raw(), wrap_ref<Rep>(-i128{x}));
    ASSERT_EQ(neg_sat(qx).raw(), sat_ref<Rep>(-i128{x}));
    ASSERT_EQ(abs_sat(qx).raw(), sat_ref<Rep>(x < 0 ? -i128{x} : i128{x}));
    Q acc = qx;
    acc += Q::from_raw(1);
    acc -= Q::from_raw(2);
    ASSERT_EQ(acc.raw(), wrap_ref<Rep>(i128{x} - 1));
  }
  EXPECT_EQ(add_sat(Q::max(), Q::from_raw(1)), Q::max());
  EXPECT_EQ(sub_sat(Q::min(), Q::from_raw(1)), Q::min());
  EXPECT_EQ(Q::max() + Q::from_raw(1), Q::min());  // documented wrap
  EXPECT_EQ(neg_sat(Q::min()), Q::max());
  EXPECT_EQ(-Q::min(), Q::min());
  EXPECT_TRUE(Q::min() < Q::max() && Q::max() > Q::min() && Q::min() <= Q::min() && Q::max() >= Q::max() && Q::min() != Q::max());
}

TEST(FixedTypeTest, AddSubWrapAndSaturate) {
  check_add_sub<Q1_15>();
  check_add_sub<Q8_8>();
  check_add_sub<Q16_16>();
  check_add_sub<Q2_30>();
}

// ---------------------------------------------------------------------------
// Multiplication and the wide accumulator
// ---------------------------------------------------------------------------
template <typename Out, typename A, typename B>
void check_mul(int random_pairs) {
  SCOPED_TRACE(testing::Message() << A::kFracBits << "*" << B::kFracBits << "->" << Out::kFracBits);
  using Rep = typename Out::rep;
  const int d = Out::kFracBits - A::kFracBits - B::kFracBits;
  std::vector<int32_t> ea = raw_samples<A>(0), eb = raw_samples<B>(0);
  std::vector<std::pair<int32_t, int32_t>> pairs;
  auto clip = [](int32_t v, auto q) { return static_cast<int32_t>(static_cast<typename decltype(q)::rep>(v)); };
  std::mt19937_64 rng(15);
  // Edge x edge (int16 formats: a thinned set of all values), then random.
  for (size_t i = 0; i < ea.size(); i += (ea.size() > 200 ? 331 : 1)) {
    for (size_t j = 0; j < eb.size(); j += (eb.size() > 200 ? 331 : 1)) pairs.push_back({ea[i], eb[j]});
  }
  for (int i = 0; i < random_pairs; ++i) pairs.push_back({clip(rand_s32(rng), A{}), clip(rand_s32(rng), B{})});
  for (const auto& [x, y] : pairs) {
    const A a = A::from_raw(static_cast<typename A::rep>(x));
    const B b = B::from_raw(static_cast<typename B::rep>(y));
    const i128 p = i128{x} * y;
    i128 want[4];
    for (int m = 0; m < 4; ++m) want[m] = rescale_ref(p, d, kModes[m]);
    ASSERT_EQ(mul_floor<Out>(a, b).raw(), wrap_ref<Rep>(want[0])) << x << " " << y;
    ASSERT_EQ(mul_trunc<Out>(a, b).raw(), wrap_ref<Rep>(want[2])) << x << " " << y;
    ASSERT_EQ(mul_round<Out>(a, b).raw(), wrap_ref<Rep>(want[3])) << x << " " << y;
    ASSERT_EQ(mul_floor_sat<Out>(a, b).raw(), sat_ref<Rep>(want[0])) << x << " " << y;
    ASSERT_EQ(mul_trunc_sat<Out>(a, b).raw(), sat_ref<Rep>(want[2])) << x << " " << y;
    ASSERT_EQ(mul_round_sat<Out>(a, b).raw(), sat_ref<Rep>(want[3])) << x << " " << y;
    // The stated bound against the double product, where it is in range.
    const long double exact = std::ldexp(static_cast<long double>(x) * y, d);
    if (std::fabs(exact) < std::ldexp(1.0L, Out::kBits - 1) - 1) {
      EXPECT_LE(std::fabs(mul_round<Out>(a, b).raw() - exact), 0.5L);
      EXPECT_LT(std::fabs(mul_floor<Out>(a, b).raw() - exact), 1.0L);
    }
  }
}

TEST(FixedMulTest, AllRoundingsAgainstExactProduct) {
  check_mul<Q16_16, Q16_16, Q16_16>(200000);
  check_mul<Q16_16, Q2_30, Q16_16>(100000);
  check_mul<Q2_30, Q2_30, Q2_30>(100000);
  check_mul<Q28_4, Q12_4, Q12_4>(50000);      // int16 x int16, 32-bit path
  check_mul<Q1_15, Q1_15, Q1_15>(100000);     // int16 x int16 -> int16
  check_mul<Q8_8, Q8_8, Q8_8>(100000);
  check_mul<Q2_30, Q1_15, Q1_15>(50000);      // no shift
  check_mul<Q2_30, Q8_8, Q8_8>(50000);        // left shift, 64-bit path
  check_mul<Q16_16, Q24_8, Q4_12>(50000);
  check_mul<Q24_8, Q16_16, Q16_16>(50000);
  // Ties: 1.5 ulp and -1.5 ulp of Q16_16.
  const Q16_16 one_and_half = Q16_16::from_raw(3 << 15), ulp = Q16_16::from_raw(1);
  EXPECT_EQ(mul_round<Q16_16>(one_and_half, ulp).raw(), 2);
  EXPECT_EQ(mul_round<Q16_16>(-one_and_half, ulp).raw(), -1);
  EXPECT_EQ(mul_trunc<Q16_16>(-one_and_half, ulp).raw(), -1);
  EXPECT_EQ(mul_floor<Q16_16>(-one_and_half, ulp).raw(), -2);
  EXPECT_EQ(mul_round_sat<Q16_16>(Q16_16::max(), Q16_16::max()), Q16_16::max());
  EXPECT_EQ(mul_round_sat<Q16_16>(Q16_16::min(), Q16_16::max()), Q16_16::min());
  EXPECT_EQ(mul_round_sat<Q1_15>(Q1_15::min(), Q1_15::min()), Q1_15::max());  // (-1)^2 = 1 does not fit
}

TEST(FixedMulTest, WideAccumulator) {
  std::mt19937_64 rng(16);
  for (int i = 0; i < 100000; ++i) {
    const Q16_16 a = Q16_16::from_raw(rand_s32(rng)), b = Q16_16::from_raw(rand_s32(rng));
    const Q2_30 c = Q2_30::from_raw(rand_s32(rng) >> 1);  // within +-2^30
    const Q16_16 e = Q16_16::from_raw(rand_s32(rng));
    Wide<32> acc = mul_wide(a, b);
    acc = mac(acc, a, e);
    acc = msc(acc, b, e);
    const i128 exact = i128{a.raw()} * b.raw() + i128{a.raw()} * e.raw() - i128{b.raw()} * e.raw();
    ASSERT_EQ(acc.raw(), static_cast<int64_t>(static_cast<uint64_t>(static_cast<u128>(exact))));  // modulo 2^64
    if (exact < (i128{1} << 62) && exact > -(i128{1} << 62)) {
      ASSERT_EQ(convert_round_sat<Q16_16>(acc).raw(), sat_ref<int32_t>(div_ref(exact, i128{1} << 16, Mode::round)));
      ASSERT_EQ(convert_floor<Q24_8>(acc).raw(), wrap_ref<int32_t>(div_ref(exact, i128{1} << 24, Mode::floor)));
    }
    const Wide<46> w = mul_wide(c, a) + mul_wide(c, b) - mul_wide(c, e);
    const i128 ew = i128{c.raw()} * a.raw() + i128{c.raw()} * b.raw() - i128{c.raw()} * e.raw();
    ASSERT_EQ(w.raw(), static_cast<int64_t>(ew));  // exact: |c| <= 2^30 keeps it below 2^63
    ASSERT_EQ(convert_round_sat<Q16_16>(w).raw(), sat_ref<int32_t>(div_ref(ew, i128{1} << 30, Mode::round)));
  }
}

// ---------------------------------------------------------------------------
// Reciprocal and division
// ---------------------------------------------------------------------------
TEST(FixedRecipTest, SeedTableRegenerates) {
  for (int i = 0; i < 256; ++i) {
    const double want = std::floor(33554432.0 / (513 + 2 * i) + 0.5);  // 2^25 / (513 + 2i), never a tie
    ASSERT_EQ(detail::kRecipSeed.v[i], want) << i;
    // The seed's relative error over its interval, which the Newton bounds rest on.
    for (const double mu : {0.5 + i / 512.0, 0.5 + (i + 1) / 512.0}) {
      EXPECT_LE(std::fabs(1.0 - mu * detail::kRecipSeed.v[i] / 32768.0), std::ldexp(1.0, -9) * 1.0079) << i;
    }
  }
}

// Bounds of recip_mant_fast: 0 <= 2^63/m - result <= kFastDeficit, and
// relative to 2^63/m below 2^-17.999 (the seed's e^2 <= 2^-18 plus the floors).
constexpr uint32_t kFastDeficit = 16384;
const long double kFastRel = std::exp2(-17.999L);

void check_recip_mant(uint32_t m) {
  const uint64_t exact = (uint64_t{1} << 63) / m;  // floor; 2^32 for m = 2^31
  const uint64_t clipped = exact > UINT32_MAX ? UINT32_MAX : exact;
  ASSERT_EQ(recip_mant(m), clipped) << m;
  const uint32_t fast = recip_mant_fast(m);
  ASSERT_LE(fast, exact) << m;
  ASSERT_LE(exact - fast, kFastDeficit) << m;
  // Relative, against the real quotient in long double.
  const long double q = std::ldexp(1.0L, 63) / m;
  ASSERT_LT((q - fast) / q, kFastRel) << m;
}

TEST(FixedRecipTest, MantissaExactAndFastBound) {
  // Every seed interval boundary and its neighbours.
  for (uint64_t i = 0; i <= 256; ++i) {
    for (int64_t e = -3; e <= 3; ++e) {
      const int64_t m = (int64_t{1} << 31) + static_cast<int64_t>(i << 23) + e;
      if (m >= (int64_t{1} << 31) && m <= UINT32_MAX) check_recip_mant(static_cast<uint32_t>(m));
    }
  }
  // Both ends of the range exhaustively, and a dense sweep with random offsets.
  for (uint32_t j = 0; j < (1u << 16); ++j) {
    check_recip_mant(0x80000000u + j);
    check_recip_mant(0xFFFFFFFFu - j);
  }
  std::mt19937_64 rng(17);
  for (uint32_t j = 0; j < (1u << 20); ++j) check_recip_mant(0x80000000u + (j << 11) + static_cast<uint32_t>(rng() & 0x7FF));
}

// The whole 2^31-mantissa range: about two minutes without sanitizers.
// Run with --gtest_also_run_disabled_tests.
TEST(FixedRecipTest, DISABLED_MantissaExhaustive) {
  for (uint64_t m = 0x80000000u; m <= UINT32_MAX; ++m) check_recip_mant(static_cast<uint32_t>(m));
}

TEST(FixedRecipTest, RecipOfAnyDivisor) {
  std::vector<uint32_t> ds = edge_u32();
  for (uint32_t d = 1; d <= (1u << 16); ++d) ds.push_back(d);
  std::mt19937_64 rng(18);
  for (int i = 0; i < 300000; ++i) ds.push_back(rand_u32(rng));
  for (const uint32_t d0 : ds) {
    const uint32_t d = d0 ? d0 : 1;  // 0 is treated as 1
    const Recip r = recip(d0), f = recip_fast(d0);
    ASSERT_EQ(r.shift, static_cast<uint32_t>(63 - clz32(d))) << d0;
    ASSERT_EQ(f.shift, r.shift);
    ASSERT_GE(r.mant, 0x80000000u);
    const u128 exact = (u128{1} << r.shift) / d;
    ASSERT_EQ(r.mant, exact > UINT32_MAX ? u128{UINT32_MAX} : exact) << d0;
    ASSERT_LE(f.mant, exact);
    ASSERT_LE(exact - f.mant, kFastDeficit);
  }
}

TEST(FixedRecipTest, PerPixelQuotient) {
  std::mt19937_64 rng(19);
  std::vector<int32_t> ns = edge_s32();
  std::vector<uint32_t> ds = edge_u32();
  for (int i = 0; i < 400; ++i) {
    ns.push_back(rand_s32(rng));
    ds.push_back(rand_u32(rng));
  }
  long double worst_fast_rel = 0;
  for (const int32_t n : ns) {
    for (const uint32_t d0 : ds) {
      const uint32_t d = d0 ? d0 : 1;
      const Recip r = recip(d0), f = recip_fast(d0);
      for (uint32_t k = 0; k <= 32; k += 1 + (rng() % 8)) {
        const i128 num = i128{n} << k;
        const i128 fq = div_ref(num, d, Mode::floor);
        if (fq >= (i128{1} << 31) || fq < -(i128{1} << 31)) continue;  // the stated domain |q| < 2^31
        const int64_t got = mul_recip_floor(n, r, k);
        if (n >= 0) {
          ASSERT_TRUE(got == fq || got == fq - 1) << n << "/" << d << " k=" << k;
        } else {
          ASSERT_TRUE(got == fq || got == fq + 1) << n << "/" << d << " k=" << k;
        }
        const long double q = std::ldexp(static_cast<long double>(n), static_cast<int>(k)) / d;
        const long double err = std::fabs(mul_recip_floor(n, f, k) - q);
        ASSERT_LT(err, 1.0L + std::fabs(q) * kFastRel) << n << "/" << d << " k=" << k;
        if (std::fabs(q) > 1e6L) worst_fast_rel = std::max(worst_fast_rel, err / std::fabs(q));
      }
    }
  }
  EXPECT_GT(worst_fast_rel, 0);  // the fast path is really approximate: the bound is not vacuous
}

TEST(FixedDivTest, Div64AgainstExact) {
  std::vector<int64_t> ns = edge_s64();
  std::vector<int32_t> ds = edge_s32();
  std::mt19937_64 rng(20);
  for (int i = 0; i < 300; ++i) {
    ns.push_back(rand_s64(rng));
    ds.push_back(rand_s32(rng));
  }
  for (const int64_t n : ns) {
    for (const int32_t d : ds) {
      int64_t want;
      if (d == 0) {
        want = n > 0 ? INT32_MAX : n < 0 ? INT32_MIN : 0;
      } else {
        const i128 q = d > 0 ? div_ref(n, d, Mode::round) : div_ref(-i128{n}, -i128{d}, Mode::round);
        want = sat_ref<int32_t>(q);
      }
      ASSERT_EQ(div64_round_sat(n, d), want) << n << " / " << d;
    }
  }
  // Ties toward +infinity.
  EXPECT_EQ(div64_round_sat(1, 2), 1);
  EXPECT_EQ(div64_round_sat(-1, 2), 0);
  EXPECT_EQ(div64_round_sat(1, -2), 0);
  EXPECT_EQ(div64_round_sat(-3, 2), -1);
  EXPECT_EQ(div64_round_sat(3, -2), -1);
  EXPECT_EQ(div64_round_sat(5, 2), 3);
  EXPECT_EQ(div64_round_sat(INT64_MIN, -1), INT32_MAX);
  EXPECT_EQ(div64_round_sat(-(int64_t{1} << 31), 1), INT32_MIN);
}

TEST(FixedDivTest, ReciprocalDivisionIsExact) {
  std::vector<int32_t> es = edge_s32();
  for (const int32_t n : es) {
    for (const int32_t d : es) {
      for (uint32_t k = 0; k < 32; ++k) {
        ASSERT_EQ(div_shl_round_sat(n, d, k), div64_round_sat(int64_t{n} * (int64_t{1} << k), d)) << n << " " << d << " " << k;
      }
    }
  }
  std::mt19937_64 rng(21);
  for (int i = 0; i < 1000000; ++i) {
    const int32_t n = rand_s32(rng), d = rand_s32(rng);
    const uint32_t k = static_cast<uint32_t>(rng() % 32);
    ASSERT_EQ(div_shl_round_sat(n, d, k), div64_round_sat(int64_t{n} * (int64_t{1} << k), d)) << n << " " << d << " " << k;
  }
  // Exact ties near every divisor magnitude: n / d = j + 1/2.
  for (int s = 1; s < 31; ++s) {
    const int32_t d = int32_t{1} << s;
    for (const int32_t j : {0, 1, 7, 1000}) {
      const int64_t n = (int64_t{2} * j + 1) * (d / 2);
      if (n > INT32_MAX) continue;
      EXPECT_EQ(div_shl_round_sat(static_cast<int32_t>(n), d, 0), j + 1);
      EXPECT_EQ(div_shl_round_sat(static_cast<int32_t>(-n), d, 0), -j);
    }
  }
}

TEST(FixedDivTest, TypedDivision) {
  const Q16_16 one = Q16_16::one(), three = Q16_16::from_int(3);
  EXPECT_EQ(div_round_sat<Q16_16>(one, three).raw(), 21845);      // 65536/3 = 21845.33
  EXPECT_EQ(div_round_sat<Q16_16>(-one, three).raw(), -21845);
  EXPECT_EQ(div_round_sat<Q16_16>(Q16_16::from_raw(1), Q16_16::from_int(2)).raw(), 1);  // 1/2 ulp -> up
  EXPECT_EQ(div_round_sat<Q16_16>(Q16_16::from_raw(-1), Q16_16::from_int(2)).raw(), 0);
  EXPECT_EQ(div_round_sat<Q16_16>(one, Q16_16{}), Q16_16::max());
  EXPECT_EQ(div_round_sat<Q16_16>(-one, Q16_16{}), Q16_16::min());
  EXPECT_EQ(div_round_sat<Q16_16>(Q16_16{}, Q16_16{}), Q16_16{});
  EXPECT_EQ(div_round_sat<Q8_8>(Q16_16::from_int(1000), one), Q8_8::max());  // saturates into int16
  EXPECT_EQ(div_round_sat<Q2_30>(Q16_16::from_int(1), Q16_16::from_int(3)).raw(), 357913941);  // 2^30/3
  // Mixed formats against the long double quotient: error <= 1/2 ulp where in range.
  std::mt19937_64 rng(22);
  for (int i = 0; i < 200000; ++i) {
    const Q24_8 a = Q24_8::from_raw(rand_s32(rng));
    const Q2_30 b = Q2_30::from_raw(rand_s32(rng));
    const Q16_16 c = Q16_16::from_raw(rand_s32(rng));
    if (c.raw() == 0) continue;
    const long double q1 = std::ldexp(static_cast<long double>(a.raw()), 16 + 16 - 8) / c.raw();  // Q24_8 / Q16_16 -> Q16_16
    const long double q2 = std::ldexp(static_cast<long double>(b.raw()), 16 + 16 - 30) / c.raw();  // Q2_30 / Q16_16 -> Q16_16
    if (std::fabs(q1) < 2147483647.0L) ASSERT_LE(std::fabs(div_round_sat<Q16_16>(a, c).raw() - q1), 0.5L) << a.raw() << " / " << c.raw();
    if (std::fabs(q2) < 2147483647.0L) ASSERT_LE(std::fabs(div_round_sat<Q16_16>(b, c).raw() - q2), 0.5L) << b.raw() << " / " << c.raw();
    if (q1 >= 2147483647.5L) ASSERT_EQ(div_round_sat<Q16_16>(a, c), Q16_16::max());
    if (q1 <= -2147483648.5L) ASSERT_EQ(div_round_sat<Q16_16>(a, c), Q16_16::min());
  }
}

// ---------------------------------------------------------------------------
// Square roots
// ---------------------------------------------------------------------------
bool is_floor_sqrt(uint64_t x, uint64_t y) { return u128{y} * y <= x && u128{y + 1} * (y + 1) > x; }

TEST(FixedSqrtTest, Isqrt32) {
  for (uint32_t x = 0; x < (1u << 24); ++x) ASSERT_TRUE(is_floor_sqrt(x, isqrt32(x))) << x;
  for (uint64_t k = 1; k <= 0xFFFF; ++k) {  // every place the floor steps
    ASSERT_EQ(isqrt32(static_cast<uint32_t>(k * k)), k);
    ASSERT_EQ(isqrt32(static_cast<uint32_t>(k * k - 1)), k - 1);
  }
  for (uint32_t j = 0; j < (1u << 20); ++j) ASSERT_TRUE(is_floor_sqrt(UINT32_MAX - j, isqrt32(UINT32_MAX - j)));
  std::mt19937_64 rng(23);
  for (int i = 0; i < 1000000; ++i) {
    const uint32_t x = static_cast<uint32_t>(rng());
    ASSERT_TRUE(is_floor_sqrt(x, isqrt32(x))) << x;
  }
  // Against double's correctly rounded sqrt.
  for (const uint32_t x : edge_u32()) EXPECT_EQ(isqrt32(x), static_cast<uint32_t>(std::floor(std::sqrt(static_cast<double>(x))))) << x;
}

// Every 2^32 input: about two minutes without sanitizers.
TEST(FixedSqrtTest, DISABLED_Isqrt32Exhaustive) {
  for (uint64_t x = 0; x <= UINT32_MAX; ++x) ASSERT_TRUE(is_floor_sqrt(x, isqrt32(static_cast<uint32_t>(x)))) << x;
}

TEST(FixedSqrtTest, Isqrt64) {
  std::vector<uint64_t> xs;
  for (int k = 0; k < 64; ++k) {
    const uint64_t p = uint64_t{1} << k;
    xs.insert(xs.end(), {p - 1, p, p + 1});
  }
  xs.push_back(UINT64_MAX);
  std::mt19937_64 rng(24);
  auto around_square = [&](uint64_t r) {  // r^2 - 1, r^2, r^2 + 1, r^2 + 2r (the last below (r+1)^2)
    const uint64_t sq = r * r;
    xs.insert(xs.end(), {sq - (r > 0), sq, sq + 1, sq + 2 * r});
  };
  for (uint64_t r = UINT32_MAX - 20000; r <= UINT32_MAX; ++r) around_square(r);
  for (uint64_t r = 0x10000; r < 0x10000 + 20000; ++r) around_square(r);  // just above 2^32 inputs
  for (int i = 0; i < 300000; ++i) {
    around_square(rng() >> 32 >> (rng() % 32));
    xs.push_back(rng() >> (rng() % 64));
  }
  for (const uint64_t x : xs) {
    const uint32_t y = isqrt64(x);
    ASSERT_TRUE(is_floor_sqrt(x, y)) << x;
    // Round to nearest: y - 1/2 <= sqrt(x) < y + 1/2, i.e. (2y - 1)^2 <= 4x < (2y + 1)^2 for y > 0.
    const i128 yr = static_cast<i128>(isqrt64_round(x));
    ASSERT_TRUE((yr == 0 || (2 * yr - 1) * (2 * yr - 1) <= i128{x} * 4) && i128{x} * 4 < (2 * yr + 1) * (2 * yr + 1)) << x;
  }
  EXPECT_EQ(isqrt64(UINT64_MAX), UINT32_MAX);
  EXPECT_EQ(isqrt64_round(UINT64_MAX), uint64_t{1} << 32);
}

TEST(FixedSqrtTest, SqrtQ16_16) {
  std::vector<int32_t> raws;
  for (int32_t r = 0; r < (1 << 20); ++r) raws.push_back(r);
  std::mt19937_64 rng(25);
  for (int i = 0; i < 300000; ++i) raws.push_back(rand_s32(rng) & INT32_MAX);
  for (const int32_t r : edge_s32()) raws.push_back(r);
  for (const int32_t r : raws) {
    const Q16_16 x = Q16_16::from_raw(r);
    if (r <= 0) {
      ASSERT_EQ(sqrt_q16_16_floor(x).raw(), 0);
      ASSERT_EQ(sqrt_q16_16_round(x).raw(), 0);
      continue;
    }
    // long double holds r * 2^16 exactly and its sqrt is correctly rounded
    // to 64 bits: never confused with an integer below 2^24.
    const long double s = std::sqrt(std::ldexp(static_cast<long double>(r), 16));
    ASSERT_EQ(sqrt_q16_16_floor(x).raw(), static_cast<int32_t>(std::floor(s))) << r;
    ASSERT_EQ(sqrt_q16_16_round(x).raw(), static_cast<int32_t>(std::floor(s + 0.5L))) << r;
  }
  EXPECT_EQ(sqrt_q16_16_floor(Q16_16::from_int(4)), Q16_16::from_int(2));
  EXPECT_EQ(sqrt_q16_16_round(Q16_16::from_ratio(9, 4)), Q16_16::from_ratio(3, 2));
}

// Largest singular value in long double, from the eigenvalues of A^T A in the
// form without cancellation.
long double norm2_ref(long double a, long double b, long double c, long double d) {
  const long double e11 = a * a + c * c, e22 = b * b + d * d, e12 = a * b + c * d;
  return std::sqrt((e11 + e22 + std::sqrt((e11 - e22) * (e11 - e22) + 4 * e12 * e12)) / 2);
}

TEST(FixedSqrtTest, Mat2Norm2) {
  auto q = [](long double v) { return Q16_16::from_raw(static_cast<int32_t>(std::llround(v * 65536))); };
  EXPECT_EQ(mat2_norm2_q16(Q16_16::one(), {}, {}, Q16_16::one()), Q16_16::one());
  EXPECT_EQ(mat2_norm2_q16(Q16_16::from_int(3), {}, {}, Q16_16::from_int(-2)), Q16_16::from_int(3));
  EXPECT_EQ(mat2_norm2_q16({}, {}, {}, {}), Q16_16{});
  EXPECT_EQ(mat2_norm2_q16(Q16_16::one(), Q16_16::one(), {}, Q16_16::one()).raw(), 106040);  // golden ratio 1.6180340 * 2^16 = 106039.56
  EXPECT_EQ(mat2_norm2_q16(Q16_16::max(), Q16_16::max(), Q16_16::max(), Q16_16::max()), Q16_16::max());
  // |a + d| >= 32768: the halved regime, <= 3 ulp.
  EXPECT_NEAR(mat2_norm2_q16(Q16_16::from_int(30000), {}, {}, Q16_16::from_int(30000)).raw(), 30000 * 65536, 3);
  EXPECT_NEAR(mat2_norm2_q16(Q16_16::from_int(20000), Q16_16::from_int(20000), Q16_16::from_int(-20000), Q16_16::from_int(20000)).raw(),
              std::sqrt(2.0) * 20000 * 65536, 3);
  EXPECT_NEAR(mat2_norm2_q16(Q16_16::min(), {}, {}, Q16_16::min()).raw(), INT32_MAX, 0);  // 32768.0 saturates
  // A rotation scaled by 1.3: exactly the VDS threshold scale.
  for (uint32_t a = 0; a < 65536; a += 97) {
    const long double t = a * 2 * M_PIl / 65536;
    const Q16_16 c = q(1.3L * std::cos(t)), s = q(1.3L * std::sin(t));
    const long double ref = norm2_ref(c.raw(), -s.raw(), s.raw(), c.raw());
    EXPECT_LE(std::fabs(mat2_norm2_q16(c, -s, s, c).raw() - ref), 1.0L);
  }
  std::mt19937_64 rng(26);
  long double worst_small = 0, worst_large = 0;
  for (int i = 0; i < 300000; ++i) {
    const int shift = static_cast<int>(rng() % 32);
    int32_t m[4];
    for (int32_t& v : m) v = static_cast<int32_t>(rng()) >> shift;
    const long double ref = norm2_ref(m[0], m[1], m[2], m[3]);
    const int32_t got = mat2_norm2_q16(Q16_16::from_raw(m[0]), Q16_16::from_raw(m[1]), Q16_16::from_raw(m[2]), Q16_16::from_raw(m[3])).raw();
    if (ref >= INT32_MAX) {
      ASSERT_EQ(got, INT32_MAX);
      continue;
    }
    const bool small = std::abs(int64_t{m[0]} + m[3]) < (int64_t{1} << 31) && std::abs(int64_t{m[0]} - m[3]) < (int64_t{1} << 31) &&
                       std::abs(int64_t{m[2]} + m[1]) < (int64_t{1} << 31) && std::abs(int64_t{m[2]} - m[1]) < (int64_t{1} << 31);
    const long double err = std::fabs(got - ref);
    ASSERT_LE(err, small ? 1.0L : 3.0L) << m[0] << " " << m[1] << " " << m[2] << " " << m[3];
    (small ? worst_small : worst_large) = std::max(small ? worst_small : worst_large, err);
  }
  EXPECT_GT(worst_large, 0);  // both regimes were exercised
  EXPECT_GT(worst_small, 0);
}

// ---------------------------------------------------------------------------
// Sine, cosine, atan2
// ---------------------------------------------------------------------------
TEST(FixedTrigTest, TablesRegenerate) {
  for (int i = 0; i <= 256; ++i) {
    ASSERT_EQ(detail::kSinQuarterQ1_31[i], std::llround(std::sin(i * M_PI / 512) * 2147483648.0)) << i;
    ASSERT_EQ(detail::kAtanTurnsQ18[i], std::llround(std::atan(i / 256.0) / (2 * M_PI) * 262144.0)) << i;
  }
  EXPECT_EQ(detail::kSinQuarterQ1_31[257], detail::kSinQuarterQ1_31[255]);
  EXPECT_EQ(detail::kAtanTurnsQ18[257], detail::kAtanTurnsQ18[256]);
}

TEST(FixedTrigTest, SinCosQ1_15AllAngles) {
  double worst = 0;
  for (uint32_t a = 0; a < 65536; ++a) {
    const uint16_t a16 = static_cast<uint16_t>(a);
    const double t = a * 2 * M_PI / 65536;
    const int s = sin_q1_15(a16).raw(), c = cos_q1_15(a16).raw();
    ASSERT_LE(std::fabs(s - std::sin(t) * 32768), 1.0) << a;
    ASSERT_LE(std::fabs(c - std::cos(t) * 32768), 1.0) << a;
    if (std::fabs(std::sin(t)) < 1 - 1.0 / 65536) worst = std::max(worst, std::fabs(s - std::sin(t) * 32768));
    // Exact symmetries.
    ASSERT_EQ(sin_q1_15(static_cast<uint16_t>(0u - a)).raw(), -s) << a;
    ASSERT_EQ(cos_q1_15(static_cast<uint16_t>(0u - a)).raw(), c) << a;
    ASSERT_EQ(sin_q1_15(static_cast<uint16_t>(a + 0x8000)).raw(), -s) << a;
  }
  EXPECT_LE(worst, 0.66);  // away from +-1.0 the only large term is the final rounding
  EXPECT_EQ(sin_q1_15(0).raw(), 0);
  EXPECT_EQ(sin_q1_15(0x4000).raw(), 32767);
  EXPECT_EQ(sin_q1_15(0xC000).raw(), -32767);
  EXPECT_EQ(cos_q1_15(0x4000).raw(), 0);
}

TEST(FixedTrigTest, SinCosQ2_30) {
  // 2^24 angles evenly over the turn (every 256th), then random angles.
  double worst = 0;
  auto check = [&](uint32_t a) {
    const double t = a * (2 * M_PI / 4294967296.0);
    const double es = std::fabs(sin_q2_30(a).raw() - std::sin(t) * 1073741824.0);
    const double ec = std::fabs(cos_q2_30(a).raw() - std::cos(t) * 1073741824.0);
    worst = std::max(worst, std::max(es, ec));
  };
  for (uint32_t j = 0; j < (1u << 24); ++j) check(j << 8);
  std::mt19937_64 rng(27);
  for (int i = 0; i < 2000000; ++i) check(static_cast<uint32_t>(rng()));
  for (uint32_t i = 0; i <= 256; ++i) {  // table points and their neighbours, each quadrant
    for (uint32_t q = 0; q < 4; ++q) {
      for (const int32_t e : {-2, -1, 0, 1, 2}) check((q << 30) + (i << 22) + static_cast<uint32_t>(e));
    }
  }
  EXPECT_LT(worst, 1.0);
  EXPECT_EQ(sin_q2_30(0).raw(), 0);
  EXPECT_EQ(sin_q2_30(1u << 30).raw(), 1 << 30);
  EXPECT_EQ(sin_q2_30(1u << 31).raw(), 0);
  EXPECT_EQ(sin_q2_30(3u << 30).raw(), -(1 << 30));
  EXPECT_EQ(cos_q2_30(0).raw(), 1 << 30);
  for (int i = 0; i < 100000; ++i) {
    const uint32_t a = static_cast<uint32_t>(rng());
    ASSERT_EQ(sin_q2_30(0u - a).raw(), -sin_q2_30(a).raw());
    ASSERT_EQ(cos_q2_30(0u - a).raw(), cos_q2_30(a).raw());
  }
}

TEST(FixedTrigTest, Atan2) {
  double worst = 0;
  auto check = [&](int32_t y, int32_t x) {
    const uint16_t got = atan2_angle16(y, x);
    if (x == 0 && y == 0) {
      ASSERT_EQ(got, 0);
      return;
    }
    double ref = std::atan2(static_cast<double>(y), static_cast<double>(x)) / (2 * M_PI) * 65536.0;
    if (ref < 0) ref += 65536.0;
    double d = std::fabs(got - ref);
    d = std::min(d, 65536.0 - d);  // circular distance
    ASSERT_LE(d, 1.0) << y << " " << x;
    worst = std::max(worst, d);
  };
  for (int32_t y = -200; y <= 200; ++y) {
    for (int32_t x = -200; x <= 200; ++x) check(y, x);
  }
  const std::vector<int32_t> es = edge_s32();
  for (const int32_t y : es) {
    for (const int32_t x : es) check(y, x);
  }
  std::mt19937_64 rng(28);
  for (int i = 0; i < 1000000; ++i) check(rand_s32(rng), rand_s32(rng));
  // Points on a large circle at every 16-bit angle.
  for (uint32_t a = 0; a < 65536; ++a) {
    const double t = a * 2 * M_PI / 65536;
    check(static_cast<int32_t>(std::lround(std::sin(t) * 1e9)), static_cast<int32_t>(std::lround(std::cos(t) * 1e9)));
  }
  EXPECT_LE(worst, 0.65);
  // Axes and diagonals exactly.
  EXPECT_EQ(atan2_angle16(0, 5), 0);
  EXPECT_EQ(atan2_angle16(5, 0), 0x4000);
  EXPECT_EQ(atan2_angle16(0, -5), 0x8000);
  EXPECT_EQ(atan2_angle16(-5, 0), 0xC000);
  EXPECT_EQ(atan2_angle16(7, 7), 0x2000);
  EXPECT_EQ(atan2_angle16(7, -7), 0x6000);
  EXPECT_EQ(atan2_angle16(-7, -7), 0xA000);
  EXPECT_EQ(atan2_angle16(-7, 7), 0xE000);
  EXPECT_EQ(atan2_angle16(INT32_MIN, INT32_MIN), 0xA000);
}

// ---------------------------------------------------------------------------
// Vectors and matrices
// ---------------------------------------------------------------------------
int32_t round_sat_ref(i128 v, int s) { return static_cast<int32_t>(sat_ref<int32_t>(div_ref(v, i128{1} << s, Mode::round))); }

TEST(FixedVectorTest, DotCrossMatVec) {
  std::mt19937_64 rng(29);
  auto q16 = [&] { return Q16_16::from_raw(rand_s32(rng) >> 1); };  // within +-2^30: sums stay exact
  for (int i = 0; i < 100000; ++i) {
    const Vec3<Q16_16> a{q16(), q16(), q16()}, b{q16(), q16(), q16()};
    const i128 ax = a.x.raw(), ay = a.y.raw(), az = a.z.raw(), bx = b.x.raw(), by = b.y.raw(), bz = b.z.raw();
    ASSERT_EQ(dot3_round_sat<Q16_16>(a, b).raw(), round_sat_ref(ax * bx + ay * by + az * bz, 16));
    const Vec3<Q16_16> c = cross3_round_sat<Q16_16>(a, b);
    ASSERT_EQ(c.x.raw(), round_sat_ref(ay * bz - az * by, 16));
    ASSERT_EQ(c.y.raw(), round_sat_ref(az * bx - ax * bz, 16));
    ASSERT_EQ(c.z.raw(), round_sat_ref(ax * by - ay * bx, 16));
    Mat3<Q2_30> m;
    for (auto& row : m.m) {
      for (Q2_30& e : row) e = Q2_30::from_raw(rand_s32(rng) >> 1);
    }
    const Vec3<Q16_16> v = mat3_mul_vec3_round_sat<Q16_16>(m, a);
    const int32_t got[3] = {v.x.raw(), v.y.raw(), v.z.raw()};
    for (int r = 0; r < 3; ++r) {
      const i128 sum = i128{m.m[r][0].raw()} * ax + i128{m.m[r][1].raw()} * ay + i128{m.m[r][2].raw()} * az;
      ASSERT_EQ(got[r], round_sat_ref(sum, 30)) << r;
    }
  }
  // Saturation: a rotation-free scale of 2 on the largest vector.
  Mat3<Q2_30> twice{};
  for (int r = 0; r < 3; ++r) twice.m[r][r] = Q2_30::from_raw(INT32_MAX);  // ~2.0
  const Vec3<Q16_16> big{Q16_16::max(), Q16_16::min(), Q16_16::from_int(1)};
  const Vec3<Q16_16> out = mat3_mul_vec3_round_sat<Q16_16>(twice, big);
  EXPECT_EQ(out.x, Q16_16::max());
  EXPECT_EQ(out.y, Q16_16::min());
  EXPECT_EQ(out.z.raw(), 131072);  // 2^31 - 1 over 2^30 times 1.0, rounded: 2.0
  // Identity in Q2_30 returns the vector unchanged.
  Mat3<Q2_30> id{};
  for (int r = 0; r < 3; ++r) id.m[r][r] = Q2_30::one();
  const Vec3<Q16_16> w{Q16_16::from_raw(-12345), Q16_16::from_raw(7), Q16_16::max()};
  const Vec3<Q16_16> wi = mat3_mul_vec3_round_sat<Q16_16>(id, w);
  EXPECT_TRUE(wi.x == w.x && wi.y == w.y && wi.z == w.z);
}

}  // namespace
}  // namespace vds
