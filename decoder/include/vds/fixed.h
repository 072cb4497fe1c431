// vds client: fixed-point arithmetic in named Q formats, with explicit rounding,
// 64-bit products, reciprocal, division, square root, sine/cosine and atan2.
// Integer only. Every function is exact or states its error bound here; the
// bounds are asserted in tests/unit/fixed_test.cpp and listed with the
// Cortex-M4 costs in docs/fixed-point.md.
#pragma once

#include <cstdint>
#include <limits>
#include <type_traits>

namespace vds {

// ===========================================================================
// Conventions
// ---------------------------------------------------------------------------
// Q<m>_<n>: a signed two's-complement number of m + n bits with n fraction
//   bits; m counts the sign bit (ARM naming). Q16_16 is int32 scaled by 2^16,
//   range [-32768, 32768); Q1_15 is int16 scaled by 2^15, range [-1, 1).
// ulp: one unit in the last place of the result format, 2^-n.
// Rounding modes, always named in the function name:
//   _floor  toward -infinity (a plain arithmetic right shift)
//   _ceil   toward +infinity
//   _trunc  toward zero
//   _round  to nearest, ties toward +infinity (floor(x + 1/2)). This is what
//           ARM's rounding instructions (SMMULR, rounding shifts) do and costs
//           one add over _floor; ties away from zero would cost a sign test.
// Overflow: functions without _sat wrap modulo 2^bits (computed through
//   unsigned arithmetic, so defined and identical on every target) and are for
//   values the caller has bounded. _sat functions clamp to the format's range.
//   Nothing here is undefined behaviour for any input.
// Binary angles: uint16_t or uint32_t where a full turn is 2^16 or 2^32, so
//   angle arithmetic wraps for free.
// ===========================================================================

// ---------------------------------------------------------------------------
// Integer helpers
// ---------------------------------------------------------------------------

// Leading zero bits; 32 (64) for zero, where the builtin alone is undefined.
// On Cortex-M the zero test folds into CLZ, which already returns 32.
constexpr int clz32(uint32_t x) { return x ? __builtin_clz(x) : 32; }
// Two 32-bit CLZs: no branch on Cortex-M, unlike the 64-bit builtin there.
constexpr int clz64(uint64_t x) {
  const uint32_t hi = static_cast<uint32_t>(x >> 32);
  return hi ? clz32(hi) : 32 + clz32(static_cast<uint32_t>(x));
}

// Bits needed for v (0 for zero).
constexpr int bitlen64(uint64_t v) { return 64 - clz64(v); }
// |v| as an unsigned value (exact for INT64_MIN too).
constexpr uint64_t abs64(int64_t v) { return v < 0 ? 0 - static_cast<uint64_t>(v) : static_cast<uint64_t>(v); }

// floor(log2(x)); -1 for zero.
constexpr int ilog2(uint32_t x) { return 31 - clz32(x); }
constexpr int ilog2_64(uint64_t x) { return 63 - clz64(x); }

// Exact products (SMULL / UMULL on Cortex-M4).
constexpr int64_t mul32x32_64(int32_t a, int32_t b) { return int64_t{a} * b; }
constexpr uint64_t umul32x32_64(uint32_t a, uint32_t b) { return uint64_t{a} * b; }

// High word of the product: floor(a*b / 2^32) (SMMUL / UMULL).
constexpr int32_t mulhi(int32_t a, int32_t b) { return static_cast<int32_t>(mul32x32_64(a, b) >> 32); }
constexpr uint32_t umulhi(uint32_t a, uint32_t b) { return static_cast<uint32_t>(umul32x32_64(a, b) >> 32); }

// floor(a*b / 2^32 + 1/2), the rounded high word (SMMULR). Never overflows:
// the largest product 2^62 gives 2^30.
constexpr int32_t mulhi_round(int32_t a, int32_t b) {
  return static_cast<int32_t>((mul32x32_64(a, b) + (int64_t{1} << 31)) >> 32);
}

// acc + a*b modulo 2^64 (SMLAL). Sums of products of int32 values need a
// caller-side bound: three products of magnitude 2^62 already overflow.
constexpr int64_t mac64(int64_t acc, int32_t a, int32_t b) {
  return static_cast<int64_t>(static_cast<uint64_t>(acc) + static_cast<uint64_t>(mul32x32_64(a, b)));
}

// Saturating narrowing and clamps.
constexpr int32_t sat_s32(int64_t v) {
  // In range exactly when the high word is the sign extension of the low one.
  return static_cast<int32_t>(v) == v ? static_cast<int32_t>(v) : v < 0 ? INT32_MIN : INT32_MAX;
}
constexpr int16_t sat_s16(int32_t v) {
  return static_cast<int16_t>(v > INT16_MAX ? INT16_MAX : v < INT16_MIN ? INT16_MIN : v);
}
constexpr uint8_t sat_u8(int32_t v) { return static_cast<uint8_t>(v > 255 ? 255 : v < 0 ? 0 : v); }
// Clamp to the signed range of `Bits` bits, [-2^(Bits-1), 2^(Bits-1) - 1] (SSAT).
template <int Bits>
constexpr int32_t sat_signed_bits(int32_t v) {
  static_assert(Bits >= 1 && Bits <= 32, "sat_signed_bits: 1..32 bits");
  constexpr int64_t hi = (int64_t{1} << (Bits - 1)) - 1;
  constexpr int64_t lo = -(int64_t{1} << (Bits - 1));
  return static_cast<int32_t>(v > hi ? hi : v < lo ? lo : v);
}
// Clamp to [0, 2^Bits - 1] (USAT).
template <int Bits>
constexpr int32_t sat_unsigned_bits(int32_t v) {
  static_assert(Bits >= 0 && Bits <= 31, "sat_unsigned_bits: 0..31 bits");
  constexpr int32_t hi = static_cast<int32_t>((int64_t{1} << Bits) - 1);
  return v > hi ? hi : v < 0 ? 0 : v;
}
constexpr int32_t clamp_s32(int32_t v, int32_t lo, int32_t hi) { return v < lo ? lo : v > hi ? hi : v; }

// Right shifts with a named rounding, for int32_t and int64_t, shift s in
// [0, bits - 1]. None of them can overflow, for any input.
template <typename T>
constexpr T shr_floor(T v, int s) {
  static_assert(std::is_same_v<T, int32_t> || std::is_same_v<T, int64_t>);
  return v >> s;
}
template <typename T>
constexpr T shr_round(T v, int s) {
  static_assert(std::is_same_v<T, int32_t> || std::is_same_v<T, int64_t>);
  // floor(v / 2^s) plus the bit just below the cut: ties go up.
  return s == 0 ? v : static_cast<T>((v >> s) + ((v >> (s - 1)) & 1));
}
template <typename T>
constexpr T shr_ceil(T v, int s) {
  static_assert(std::is_same_v<T, int32_t> || std::is_same_v<T, int64_t>);
  using U = std::make_unsigned_t<T>;
  const U mask = (U{1} << s) - 1;
  return static_cast<T>((v >> s) + ((static_cast<U>(v) & mask) != 0));
}
template <typename T>
constexpr T shr_trunc(T v, int s) {
  static_assert(std::is_same_v<T, int32_t> || std::is_same_v<T, int64_t>);
  using U = std::make_unsigned_t<T>;
  const U mask = (U{1} << s) - 1;
  // A negative v gets 2^s - 1 added before the floor shift; that cannot overflow.
  const U bias = static_cast<U>(v >> (int{sizeof(T)} * 8 - 1)) & mask;
  return static_cast<T>(v + static_cast<T>(bias)) >> s;
}

namespace detail {

enum class Rounding { floor, ceil, trunc, round };

template <Rounding R, typename T>
constexpr T shr(T v, int s) {
  if constexpr (R == Rounding::floor) return shr_floor(v, s);
  if constexpr (R == Rounding::ceil) return shr_ceil(v, s);
  if constexpr (R == Rounding::trunc) return shr_trunc(v, s);
  if constexpr (R == Rounding::round) return shr_round(v, s);
}

// A value v (int32_t or int64_t, computed in that width) with `from` fraction
// bits rescaled to `to` fraction bits and narrowed to Rep: right shifts round
// with R, left shifts are exact; out of range wraps (Sat false) or clamps
// (Sat true). |to - from| < bits of V.
template <typename Rep, Rounding R, bool Sat, typename V>
constexpr Rep rescale(V v, int from, int to) {
  static_assert(std::is_same_v<V, int32_t> || std::is_same_v<V, int64_t>);
  static_assert(sizeof(Rep) <= sizeof(V));
  constexpr V kMax = std::numeric_limits<Rep>::max();
  constexpr V kMin = std::numeric_limits<Rep>::min();
  const int d = to - from;
  if (d < 0) {
    v = shr<R>(v, -d);
  } else if (d > 0) {
    if constexpr (Sat) {
      // Clamp before shifting so the shift itself cannot overflow. kMin is a
      // multiple of 2^d (d < bits), so the floor shift is exact.
      if (v > (kMax >> d)) return static_cast<Rep>(kMax);
      if (v < (kMin >> d)) return static_cast<Rep>(kMin);
    }
    v = static_cast<V>(static_cast<std::make_unsigned_t<V>>(v) << d);
  }
  if constexpr (Sat && sizeof(Rep) < sizeof(V)) {
    if constexpr (std::is_same_v<V, int32_t>) return sat_s16(v);  // SSAT
    if constexpr (std::is_same_v<Rep, int32_t>) return sat_s32(v);
    return sat_s16(sat_s32(v));
  }
  return static_cast<Rep>(v);  // modulo 2^bits (C++20)
}

// Reached only when a compile-time constant is out of range: the call makes
// the consteval evaluation fail, so the mistake is a compile error.
void fixed_constant_out_of_range();

// A raw value in the width its arithmetic needs: Fixed raws (int16/int32) as
// int32_t, Wide raws as int64_t.
constexpr int32_t widen(int16_t v) { return v; }
constexpr int32_t widen(int32_t v) { return v; }
constexpr int64_t widen(int64_t v) { return v; }

}  // namespace detail

// ---------------------------------------------------------------------------
// Fixed<Rep, FracBits>: a value stored as Rep scaled by 2^FracBits
// ---------------------------------------------------------------------------
template <typename Rep, int FracBits>
class Fixed {
  static_assert(std::is_same_v<Rep, int16_t> || std::is_same_v<Rep, int32_t>, "Fixed: int16_t or int32_t storage");
  static_assert(FracBits >= 0 && FracBits < int{sizeof(Rep)} * 8, "Fixed: fraction bits in [0, bits)");

 public:
  using rep = Rep;
  static constexpr int kBits = int{sizeof(Rep)} * 8;
  static constexpr int kFracBits = FracBits;
  static constexpr int kIntBits = kBits - FracBits;  // including the sign bit

  constexpr Fixed() = default;

  static constexpr Fixed from_raw(Rep r) {
    Fixed f;
    f.raw_ = r;
    return f;
  }
  // i * 2^FracBits; wraps when i is outside the range (see from_int_sat).
  static constexpr Fixed from_int(int32_t i) {
    return from_raw(detail::rescale<Rep, detail::Rounding::floor, false>(i, 0, FracBits));
  }
  static constexpr Fixed from_int_sat(int32_t i) {
    return from_raw(detail::rescale<Rep, detail::Rounding::floor, true>(i, 0, FracBits));
  }
  // Compile-time constant num/den rounded to nearest (ties up), e.g.
  // Q16_16::from_ratio(13, 10) for 1.3. Out of range is a compile error.
  static consteval Fixed from_ratio(int64_t num, int64_t den) {
    if (den < 0) {
      num = -num;
      den = -den;
    }
    if (den == 0) detail::fixed_constant_out_of_range();
    // floor((2 * num * 2^F + den) / (2 * den)) computed with floor division.
    const int64_t n = 2 * num * (int64_t{1} << FracBits) + den;
    const int64_t d = 2 * den;
    int64_t q = n / d;
    if (n % d != 0 && n < 0) --q;
    if (q > std::numeric_limits<Rep>::max() || q < std::numeric_limits<Rep>::min()) {
      detail::fixed_constant_out_of_range();
    }
    return from_raw(static_cast<Rep>(q));
  }
  static constexpr Fixed max() { return from_raw(std::numeric_limits<Rep>::max()); }
  static constexpr Fixed min() { return from_raw(std::numeric_limits<Rep>::min()); }
  static constexpr Fixed one() {
    static_assert(kIntBits >= 2, "Fixed::one: 1.0 is not representable in this format");
    return from_raw(static_cast<Rep>(Rep{1} << FracBits));
  }

  constexpr Rep raw() const { return raw_; }

  constexpr int32_t to_int_floor() const { return static_cast<int32_t>(shr_floor(int32_t{raw_}, FracBits)); }
  constexpr int32_t to_int_ceil() const { return static_cast<int32_t>(shr_ceil(int32_t{raw_}, FracBits)); }
  constexpr int32_t to_int_trunc() const { return static_cast<int32_t>(shr_trunc(int32_t{raw_}, FracBits)); }
  constexpr int32_t to_int_round() const { return static_cast<int32_t>(shr_round(int32_t{raw_}, FracBits)); }

  // Wrapping arithmetic for bounded values (ADD/SUB); see add_sat/sub_sat.
  friend constexpr Fixed operator+(Fixed a, Fixed b) { return from_raw(wrap(uint32_t(a.raw_) + uint32_t(b.raw_))); }
  friend constexpr Fixed operator-(Fixed a, Fixed b) { return from_raw(wrap(uint32_t(a.raw_) - uint32_t(b.raw_))); }
  friend constexpr Fixed operator-(Fixed a) { return from_raw(wrap(0u - uint32_t(a.raw_))); }
  constexpr Fixed& operator+=(Fixed b) { return *this = *this + b; }
  constexpr Fixed& operator-=(Fixed b) { return *this = *this - b; }

  friend constexpr bool operator==(Fixed a, Fixed b) { return a.raw_ == b.raw_; }
  friend constexpr bool operator!=(Fixed a, Fixed b) { return a.raw_ != b.raw_; }
  friend constexpr bool operator<(Fixed a, Fixed b) { return a.raw_ < b.raw_; }
  friend constexpr bool operator<=(Fixed a, Fixed b) { return a.raw_ <= b.raw_; }
  friend constexpr bool operator>(Fixed a, Fixed b) { return a.raw_ > b.raw_; }
  friend constexpr bool operator>=(Fixed a, Fixed b) { return a.raw_ >= b.raw_; }

 private:
  static constexpr Rep wrap(uint32_t u) { return static_cast<Rep>(static_cast<std::make_unsigned_t<Rep>>(u)); }
  Rep raw_ = 0;
};

// The formats the client uses. int16 storage: coefficients, colours, small
// screen coordinates; int32: geometry, texture coordinates, matrices.
using Q1_15 = Fixed<int16_t, 15>;   // [-1, 1): unit-range samples, sin/cos tables in 16 bits
using Q4_12 = Fixed<int16_t, 12>;   // [-8, 8): compact matrix entries, filter weights
using Q8_8 = Fixed<int16_t, 8>;     // [-128, 128): small signed values with 1/256 steps
using Q12_4 = Fixed<int16_t, 4>;    // [-2048, 2048): screen coordinates with 1/16-pixel sub-pixel precision
using Q2_30 = Fixed<int32_t, 30>;   // [-2, 2): rotation matrices, sin/cos, unit vectors
using Q16_16 = Fixed<int32_t, 16>;  // [-32768, 32768): general purpose, camera space, texture coordinates
using Q24_8 = Fixed<int32_t, 8>;    // [-2^23, 2^23): large coordinates with 1/256 steps
using Q28_4 = Fixed<int32_t, 4>;    // [-2^27, 2^27): screen coordinates in edge setup (1/16 pixel)

// ---------------------------------------------------------------------------
// Conversions between formats: To from From, named rounding, wrap or _sat.
// ---------------------------------------------------------------------------
namespace detail {
template <typename To, Rounding R, bool Sat, typename From>
constexpr To convert(From x) {
  return To::from_raw(rescale<typename To::rep, R, Sat>(widen(x.raw()), From::kFracBits, To::kFracBits));
}
}  // namespace detail

template <typename To, typename From>
constexpr To convert_floor(From x) { return detail::convert<To, detail::Rounding::floor, false>(x); }
template <typename To, typename From>
constexpr To convert_ceil(From x) { return detail::convert<To, detail::Rounding::ceil, false>(x); }
template <typename To, typename From>
constexpr To convert_trunc(From x) { return detail::convert<To, detail::Rounding::trunc, false>(x); }
template <typename To, typename From>
constexpr To convert_round(From x) { return detail::convert<To, detail::Rounding::round, false>(x); }
template <typename To, typename From>
constexpr To convert_floor_sat(From x) { return detail::convert<To, detail::Rounding::floor, true>(x); }
template <typename To, typename From>
constexpr To convert_ceil_sat(From x) { return detail::convert<To, detail::Rounding::ceil, true>(x); }
template <typename To, typename From>
constexpr To convert_trunc_sat(From x) { return detail::convert<To, detail::Rounding::trunc, true>(x); }
template <typename To, typename From>
constexpr To convert_round_sat(From x) { return detail::convert<To, detail::Rounding::round, true>(x); }

// ---------------------------------------------------------------------------
// Saturating add, subtract, negate, absolute value (same format)
// ---------------------------------------------------------------------------
template <typename Q>
constexpr Q add_sat(Q a, Q b) {
  if constexpr (sizeof(typename Q::rep) == 2) {
    return Q::from_raw(sat_s16(int32_t{a.raw()} + b.raw()));  // SSAT
  } else {
    int32_t r;
    if (__builtin_add_overflow(a.raw(), b.raw(), &r)) return a.raw() < 0 ? Q::min() : Q::max();
    return Q::from_raw(r);
  }
}
template <typename Q>
constexpr Q sub_sat(Q a, Q b) {
  if constexpr (sizeof(typename Q::rep) == 2) {
    return Q::from_raw(sat_s16(int32_t{a.raw()} - b.raw()));
  } else {
    int32_t r;
    if (__builtin_sub_overflow(a.raw(), b.raw(), &r)) return a.raw() < 0 ? Q::min() : Q::max();
    return Q::from_raw(r);
  }
}
template <typename Q>
constexpr Q neg_sat(Q a) {
  return a == Q::min() ? Q::max() : -a;
}
template <typename Q>
constexpr Q abs_sat(Q a) {
  return a.raw() < 0 ? neg_sat(a) : a;
}

// ---------------------------------------------------------------------------
// Multiplication: the exact product (64-bit, or 32-bit for two int16
// formats), then one rounding into Out. Error <= 1/2 ulp (_round) or < 1 ulp
// (_floor) when the result is in range; wraps (or clamps for _sat) otherwise.
// ---------------------------------------------------------------------------
namespace detail {
template <typename Out, Rounding R, bool Sat, typename A, typename B>
constexpr Out mul(A a, B b) {
  constexpr int kProdFrac = A::kFracBits + B::kFracBits;
  if constexpr (sizeof(typename A::rep) == 2 && sizeof(typename B::rep) == 2 && Out::kFracBits <= kProdFrac) {
    // Two int16 values: the product fits in int32 (at most 2^30) and the
    // 32-bit shift is cheaper than a 64-bit one on Cortex-M (SMULBB).
    const int32_t p = int32_t{a.raw()} * int32_t{b.raw()};
    return Out::from_raw(rescale<typename Out::rep, R, Sat>(p, kProdFrac, Out::kFracBits));
  } else {
    const int64_t p = mul32x32_64(a.raw(), b.raw());
    return Out::from_raw(rescale<typename Out::rep, R, Sat>(p, kProdFrac, Out::kFracBits));
  }
}
}  // namespace detail

template <typename Out, typename A, typename B>
constexpr Out mul_floor(A a, B b) { return detail::mul<Out, detail::Rounding::floor, false>(a, b); }
template <typename Out, typename A, typename B>
constexpr Out mul_round(A a, B b) { return detail::mul<Out, detail::Rounding::round, false>(a, b); }
template <typename Out, typename A, typename B>
constexpr Out mul_trunc(A a, B b) { return detail::mul<Out, detail::Rounding::trunc, false>(a, b); }
template <typename Out, typename A, typename B>
constexpr Out mul_floor_sat(A a, B b) { return detail::mul<Out, detail::Rounding::floor, true>(a, b); }
template <typename Out, typename A, typename B>
constexpr Out mul_round_sat(A a, B b) { return detail::mul<Out, detail::Rounding::round, true>(a, b); }
template <typename Out, typename A, typename B>
constexpr Out mul_trunc_sat(A a, B b) { return detail::mul<Out, detail::Rounding::trunc, true>(a, b); }

// ---------------------------------------------------------------------------
// Wide<F>: a 64-bit accumulator of exact products with F fraction bits
// (SMLAL). Sums wrap modulo 2^64: the caller keeps the sum below 2^63, e.g.
// three products of int32 values stay in range when one factor of each is
// within +-2^30 (any Q2_30 matrix entry up to 1.0).
// ---------------------------------------------------------------------------
template <int F>
struct Wide {
  static_assert(F >= 0 && F <= 62, "Wide: 0..62 fraction bits");
  static constexpr int kFracBits = F;
  int64_t v = 0;
  constexpr int64_t raw() const { return v; }
  friend constexpr Wide operator+(Wide a, Wide b) {
    return {static_cast<int64_t>(static_cast<uint64_t>(a.v) + static_cast<uint64_t>(b.v))};
  }
  friend constexpr Wide operator-(Wide a, Wide b) {
    return {static_cast<int64_t>(static_cast<uint64_t>(a.v) - static_cast<uint64_t>(b.v))};
  }
};

template <typename A, typename B>
constexpr Wide<A::kFracBits + B::kFracBits> mul_wide(A a, B b) {
  return {mul32x32_64(a.raw(), b.raw())};
}
// acc + a*b and acc - a*b.
template <int F, typename A, typename B>
constexpr Wide<F> mac(Wide<F> acc, A a, B b) {
  static_assert(A::kFracBits + B::kFracBits == F, "mac: product format differs from the accumulator");
  return {mac64(acc.v, a.raw(), b.raw())};
}
template <int F, typename A, typename B>
constexpr Wide<F> msc(Wide<F> acc, A a, B b) {
  static_assert(A::kFracBits + B::kFracBits == F, "msc: product format differs from the accumulator");
  return {static_cast<int64_t>(static_cast<uint64_t>(acc.v) - static_cast<uint64_t>(mul32x32_64(a.raw(), b.raw())))};
}
// Wide results into a format: the same convert_* functions apply, e.g.
// convert_round_sat<Q16_16>(acc).

// ---------------------------------------------------------------------------
// Reciprocal and division
// ---------------------------------------------------------------------------
// 1/d ~= mant * 2^-shift, with mant in [2^31, 2^32) (a Q1.31 mantissa of a
// value in (1, 2]) and shift in [32, 63]. Built from a 256-entry table of
// 16-bit seeds (512 bytes) and Newton-Raphson steps with 32x32->64 multiplies
// only (no division instruction, no libgcc call).
struct Recip {
  uint32_t mant;
  uint32_t shift;
};

namespace detail {
// v[i] = round(2^25 / (513 + 2i)): 1/mu in Q1.15 at the centre of
// mu in [1/2 + i/512, 1/2 + (i+1)/512), which makes |1 - mu * seed| <= 2^-8.99.
struct RecipSeedTable {
  uint16_t v[256];
};
extern const RecipSeedTable kRecipSeed;
}  // namespace detail

// For m in [2^31, 2^32) (normalised: top bit set): an estimate of 2^63 / m
// after one Newton step from the seed. Never above the true value:
// 0 <= 2^63/m - result <= 16384, relative error < 2^-17.999 (e^2 <= 2^-18
// from the seed, plus the floors). Both bounds are reached near m = 2^31.
inline uint32_t recip_mant_fast(uint32_t m) {
  // m = mu * 2^32 with mu in [1/2, 1); the seed t = y0 * 2^15 with y0 ~ 1/mu.
  const uint32_t t = detail::kRecipSeed.v[(m >> 23) & 0xFF];
  // e = 1 - mu*y0 = (2^47 - m*t) / 2^47; |e| < 2^-8.99, so e*2^39 fits int32.
  const int64_t e47 = (int64_t{1} << 47) - static_cast<int64_t>(umul32x32_64(m, t));
  const int32_t e39 = static_cast<int32_t>(e47 >> 8);
  // y1 = y0 + y0*e in Q1.31: t*2^16 + t*e39 / 2^23. Newton from either side
  // lands below 1/mu (1 - mu*y1 = e^2 >= 0) and the floors only lower it.
  return static_cast<uint32_t>((int64_t{t} << 16) + (mul32x32_64(static_cast<int32_t>(t), e39) >> 23));
}

// For m in [2^31, 2^32): exactly floor(2^63 / m), except m = 2^31 where the
// true 2^32 is clipped to 2^32 - 1. So 0 <= 2^63/m - result <= 1.
inline uint32_t recip_mant(uint32_t m) {
  uint32_t y = recip_mant_fast(m);
  // Second Newton step on the exact remainder r = 2^63 - m*y, which is >= 0
  // and below 2^46.1, so r >> 15 fits 32 bits: y += r * y / 2^63.
  const uint64_t r = (uint64_t{1} << 63) - umul32x32_64(m, y);
  y += static_cast<uint32_t>(umul32x32_64(y, static_cast<uint32_t>(r >> 15)) >> 48);
  // Now y is floor(2^63/m) or one less. One less leaves a remainder above m;
  // the exact value leaves one below m, and only m = 2^31 (clipped) leaves
  // exactly m.
  const uint64_t r2 = (uint64_t{1} << 63) - umul32x32_64(m, y);
  return y + (r2 > m);
}

// Reciprocal of any d >= 1; d = 0 is treated as 1 (so it never traps).
// Exact mantissa: mant = floor(2^shift / d), clipped to 2^32 - 1 for powers of two.
inline Recip recip(uint32_t d) {
  d += (d == 0);
  const int s = clz32(d);
  return {recip_mant(d << s), static_cast<uint32_t>(63 - s)};
}
// Fast mantissa: 0 <= 2^shift/d - mant <= 16384 (relative < 2^-17.999).
inline Recip recip_fast(uint32_t d) {
  d += (d == 0);
  const int s = clz32(d);
  return {recip_mant_fast(d << s), static_cast<uint32_t>(63 - s)};
}

// floor(n * mant / 2^(shift - frac_bits)): the quotient n * 2^frac_bits / d
// from a reciprocal of d, frac_bits in [0, 32]. One multiply and a shift; the
// per-pixel perspective division (u = U * (1/W)). With q = n * 2^frac_bits / d
// and |q| < 2^31: from recip(), the result is floor(q) or one less (n > 0) or
// one more (n < 0); from recip_fast(), |result - q| < 1 + |q| * 2^-17.999.
constexpr int64_t mul_recip_floor(int32_t n, Recip r, uint32_t frac_bits) {
  return (int64_t{n} * int64_t{r.mant}) >> (r.shift - frac_bits);
}

// round(num * 2^k / den) with ties toward +infinity, saturated to int32,
// k in [0, 31]. Exact (bit-identical to div64_round_sat(num * 2^k, den)) but
// built on recip() and 32x32->64 multiplies: no 64/32 division. den = 0
// gives INT32_MAX, INT32_MIN or 0 by the sign of num.
int32_t div_shl_round_sat(int32_t num, int32_t den, uint32_t k);

// round(num / den) with ties toward +infinity, saturated to int32; den = 0 as
// above. The reference: exact, but uses the 64-bit division of libgcc
// (__aeabi_uldivmod), so keep it out of per-pixel loops.
int32_t div64_round_sat(int64_t num, int32_t den);

// a / b in format Out, rounded to nearest (ties up) and saturated; b = 0
// saturates by the sign of a (0 / 0 = 0). Exact, via div_shl_round_sat.
template <typename Out, typename A, typename B>
Out div_round_sat(A a, B b) {
  constexpr int k = Out::kFracBits + B::kFracBits - A::kFracBits;
  static_assert(k >= 0 && k <= 31, "div_round_sat: Out has too few or too many fraction bits for A / B");
  const int32_t q = div_shl_round_sat(a.raw(), b.raw(), k);
  return Out::from_raw(detail::rescale<typename Out::rep, detail::Rounding::floor, true>(q, 0, 0));
}

// ---------------------------------------------------------------------------
// Square roots (exact)
// ---------------------------------------------------------------------------
// floor(sqrt(x)). Table seed (192 x 16 bits) + one Newton step with UDIV + a
// final +-1 correction; exact for every input.
uint32_t isqrt32(uint32_t x);
// floor(sqrt(x)). isqrt32 of the top half, one Newton step through recip_mant
// (no 64-bit division) + a final +-1 correction; exact for every input.
uint32_t isqrt64(uint64_t x);
// round(sqrt(x)) to nearest (no ties exist); exact. Up to 2^32 for x near 2^64.
uint64_t isqrt64_round(uint64_t x);
// sqrt of a Q16.16 value in Q16.16, exact floor / exact round to nearest;
// negative input gives 0.
Q16_16 sqrt_q16_16_floor(Q16_16 x);
Q16_16 sqrt_q16_16_round(Q16_16 x);

// The 2-norm (largest singular value) of the 2x2 matrix [[a, b], [c, d]]:
// the scale factor of the VDS texture quality test (Cohen-Or et al., sec. 4).
// Computed as (sqrt((a+d)^2 + (c-b)^2) + sqrt((a-d)^2 + (c+b)^2)) / 2, which
// has no cancellation. Error <= 1 ulp (2^-16) when |a+-d| and |c+-b| are
// below 2^15 (32768.0), <= 3 ulp otherwise; saturates at Q16_16::max().
Q16_16 mat2_norm2_q16(Q16_16 a, Q16_16 b, Q16_16 c, Q16_16 d);

// ---------------------------------------------------------------------------
// Sine, cosine and atan2 on binary angles
// ---------------------------------------------------------------------------
namespace detail {
// sin(i * pi/512) in Q1.31 (unsigned: 1.0 is 2^31), i = 0..256, rounded to
// nearest; entry 257 repeats entry 255 (= sin of pi/2 + pi/512) so that
// interpolation at the quarter point reads a valid neighbour. 1032 bytes.
extern const uint32_t kSinQuarterQ1_31[258];
// atan(i/256) in units of 2^-18 turn, i = 0..256, rounded; entry 257 repeats
// entry 256. 516 bytes.
extern const uint16_t kAtanTurnsQ18[258];
}  // namespace detail

// angle in 2^-32 turn. Quarter-wave table + third-order Taylor expansion at
// the table point: |error| < 1 ulp (2^-30; 0.81 ulp is the largest seen);
// exact 0 and +-1.0 at multiples of a quarter turn; sin(-a) == -sin(a) exactly.
Q2_30 sin_q2_30(uint32_t angle);
Q2_30 cos_q2_30(uint32_t angle);
// angle in 2^-16 turn. Same table, linear interpolation: |error| <= 1 ulp
// (2^-15), and <= 0.66 ulp where |sin| < 1 - 2^-16; +1.0 is returned as
// 32767/32768 and -1.0 as -32767/32768, keeping sin(-a) == -sin(a) exactly.
Q1_15 sin_q1_15(uint16_t angle);
Q1_15 cos_q1_15(uint16_t angle);

// atan2(y, x) as a binary angle in 2^-16 turn, counter-clockwise from +x,
// in [0, 2^16). |error| <= 1 (2^-16 turn) for every input (0.64 is the
// largest seen); exact on the axes and diagonals; atan2(0, 0) = 0.
uint16_t atan2_angle16(int32_t y, int32_t x);

// ---------------------------------------------------------------------------
// 3-vectors and 3x3 matrices (row-major), exact 64-bit sums, one rounding
// ---------------------------------------------------------------------------
template <typename T>
struct Vec3 {
  T x, y, z;
};
template <typename T>
struct Mat3 {
  T m[3][3];  // m[row][column]
};

// The sums are exact while below 2^63 in magnitude (see Wide), then rounded
// to nearest (ties up) and saturated into Out: error <= 1/2 ulp.
template <typename Out, typename A, typename B>
constexpr Out dot3_round_sat(const Vec3<A>& a, const Vec3<B>& b) {
  return convert_round_sat<Out>(mac(mac(mul_wide(a.x, b.x), a.y, b.y), a.z, b.z));
}
template <typename Out, typename A, typename B>
constexpr Vec3<Out> cross3_round_sat(const Vec3<A>& a, const Vec3<B>& b) {
  return {convert_round_sat<Out>(msc(mul_wide(a.y, b.z), a.z, b.y)),
          convert_round_sat<Out>(msc(mul_wide(a.z, b.x), a.x, b.z)),
          convert_round_sat<Out>(msc(mul_wide(a.x, b.y), a.y, b.x))};
}
template <typename Out, typename M, typename V>
constexpr Vec3<Out> mat3_mul_vec3_round_sat(const Mat3<M>& m, const Vec3<V>& v) {
  Vec3<Out> r{};
  Out* out[3] = {&r.x, &r.y, &r.z};
  for (int i = 0; i < 3; ++i) {
    *out[i] = convert_round_sat<Out>(mac(mac(mul_wide(m.m[i][0], v.x), m.m[i][1], v.y), m.m[i][2], v.z));
  }
  return r;
}

}  // namespace vds
