// Fixed-point tables and the out-of-line functions of vds/fixed.h: exact
// division through the reciprocal, exact integer square roots, sin/cos, atan2.
#include "vds/fixed.h"

namespace vds {
namespace detail {

// ---------------------------------------------------------------------------
// Tables generated at compile time with integer arithmetic only
// ---------------------------------------------------------------------------
namespace {

// 1/mu in Q1.15 at the centre of each of 256 intervals of mu in [1/2, 1):
// 2 / (mu_lo + mu_hi) = 1024 / (513 + 2i), rounded to nearest. The centre
// value minimises max |1 - mu*y0| over the interval, the error Newton squares.
constexpr RecipSeedTable make_recip_seed() {
  RecipSeedTable t{};
  for (uint32_t i = 0; i < 256; ++i) {
    const uint32_t den = 513 + 2 * i;
    t.v[i] = static_cast<uint16_t>(((uint32_t{1} << 25) + den / 2) / den);
  }
  return t;
}

constexpr uint64_t isqrt_floor_constexpr(uint64_t x) {
  uint64_t lo = 0, hi = uint64_t{1} << 32;  // the answer is in [lo, hi)
  while (hi - lo > 1) {
    const uint64_t mid = lo + (hi - lo) / 2;
    if (mid * mid <= x) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return lo;
}

// Seeds for isqrt32: a normalised xn in [2^30, 2^32) is split into 192
// intervals by its top 8 bits (64..255); each seed is round(sqrt(centre)) =
// round(2^12 sqrt(i + 1/2)), within a relative 2^-8 of sqrt(xn).
constexpr uint32_t kSqrtSeedFirst = 64;
struct SqrtSeedTable {
  uint16_t v[192];
};
constexpr SqrtSeedTable make_sqrt_seed() {
  SqrtSeedTable t{};
  for (uint32_t i = 0; i < 192; ++i) {
    const uint64_t centre = (2 * uint64_t{i + kSqrtSeedFirst} + 1) << 23;
    const uint64_t f = isqrt_floor_constexpr(centre);
    t.v[i] = static_cast<uint16_t>(f + (centre - f * f > f));  // round to nearest
  }
  return t;
}
constexpr SqrtSeedTable kSqrtSeed = make_sqrt_seed();
static_assert(kSqrtSeed.v[0] == 32896 && kSqrtSeed.v[191] == 65472, "sqrt seed endpoints");

}  // namespace

constexpr RecipSeedTable kRecipSeed = make_recip_seed();
static_assert(kRecipSeed.v[0] == 65408 && kRecipSeed.v[255] == 32800, "reciprocal seed endpoints");

// Literal tables (irrational values). tests/unit/fixed_test.cpp recomputes
// every entry in double precision and compares exactly; the nearest value to
// a rounding tie is 0.0013 ulp (sin) and 0.00001 ulp (atan) away, far beyond
// double's error.
const uint32_t kSinQuarterQ1_31[258] = {
    0u, 13176712u, 26352928u, 39528151u, 52701887u, 65873638u,
    79042909u, 92209205u, 105372028u, 118530885u, 131685278u, 144834714u,
    157978697u, 171116733u, 184248325u, 197372981u, 210490206u, 223599506u,
    236700388u, 249792358u, 262874923u, 275947592u, 289009871u, 302061269u,
    315101295u, 328129457u, 341145265u, 354148230u, 367137861u, 380113669u,
    393075166u, 406021865u, 418953276u, 431868915u, 444768294u, 457650927u,
    470516330u, 483364019u, 496193509u, 509004318u, 521795963u, 534567963u,
    547319836u, 560051104u, 572761285u, 585449903u, 598116479u, 610760536u,
    623381598u, 635979190u, 648552838u, 661102068u, 673626408u, 686125387u,
    698598533u, 711045377u, 723465451u, 735858287u, 748223418u, 760560380u,
    772868706u, 785147934u, 797397602u, 809617249u, 821806413u, 833964638u,
    846091463u, 858186435u, 870249095u, 882278992u, 894275671u, 906238681u,
    918167572u, 930061894u, 941921200u, 953745043u, 965532978u, 977284562u,
    988999351u, 1000676905u, 1012316784u, 1023918550u, 1035481766u, 1047005996u,
    1058490808u, 1069935768u, 1081340445u, 1092704411u, 1104027237u, 1115308496u,
    1126547765u, 1137744621u, 1148898640u, 1160009405u, 1171076495u, 1182099496u,
    1193077991u, 1204011567u, 1214899813u, 1225742318u, 1236538675u, 1247288478u,
    1257991320u, 1268646800u, 1279254516u, 1289814068u, 1300325060u, 1310787095u,
    1321199781u, 1331562723u, 1341875533u, 1352137822u, 1362349204u, 1372509294u,
    1382617710u, 1392674072u, 1402678000u, 1412629117u, 1422527051u, 1432371426u,
    1442161874u, 1451898025u, 1461579514u, 1471205974u, 1480777044u, 1490292364u,
    1499751576u, 1509154322u, 1518500250u, 1527789007u, 1537020244u, 1546193612u,
    1555308768u, 1564365367u, 1573363068u, 1582301533u, 1591180426u, 1599999411u,
    1608758157u, 1617456335u, 1626093616u, 1634669676u, 1643184191u, 1651636841u,
    1660027308u, 1668355276u, 1676620432u, 1684822463u, 1692961062u, 1701035922u,
    1709046739u, 1716993211u, 1724875040u, 1732691928u, 1740443581u, 1748129707u,
    1755750017u, 1763304224u, 1770792044u, 1778213194u, 1785567396u, 1792854372u,
    1800073849u, 1807225553u, 1814309216u, 1821324572u, 1828271356u, 1835149306u,
    1841958164u, 1848697674u, 1855367581u, 1861967634u, 1868497586u, 1874957189u,
    1881346202u, 1887664383u, 1893911494u, 1900087301u, 1906191570u, 1912224073u,
    1918184581u, 1924072871u, 1929888720u, 1935631910u, 1941302225u, 1946899451u,
    1952423377u, 1957873796u, 1963250501u, 1968553292u, 1973781967u, 1978936331u,
    1984016189u, 1989021350u, 1993951625u, 1998806829u, 2003586779u, 2008291295u,
    2012920201u, 2017473321u, 2021950484u, 2026351522u, 2030676269u, 2034924562u,
    2039096241u, 2043191150u, 2047209133u, 2051150040u, 2055013723u, 2058800036u,
    2062508835u, 2066139983u, 2069693342u, 2073168777u, 2076566160u, 2079885360u,
    2083126254u, 2086288720u, 2089372638u, 2092377892u, 2095304370u, 2098151960u,
    2100920556u, 2103610054u, 2106220352u, 2108751352u, 2111202959u, 2113575080u,
    2115867626u, 2118080511u, 2120213651u, 2122266967u, 2124240380u, 2126133817u,
    2127947206u, 2129680480u, 2131333572u, 2132906420u, 2134398966u, 2135811153u,
    2137142927u, 2138394240u, 2139565043u, 2140655293u, 2141664948u, 2142593971u,
    2143442326u, 2144209982u, 2144896910u, 2145503083u, 2146028480u, 2146473080u,
    2146836866u, 2147119825u, 2147321946u, 2147443222u, 2147483648u, 2147443222u,
};

const uint16_t kAtanTurnsQ18[258] = {
    0u, 163u, 326u, 489u, 652u, 815u, 978u, 1141u, 1303u, 1466u,
    1629u, 1792u, 1954u, 2117u, 2279u, 2442u, 2604u, 2767u, 2929u, 3091u,
    3253u, 3415u, 3577u, 3738u, 3900u, 4061u, 4223u, 4384u, 4545u, 4706u,
    4867u, 5028u, 5188u, 5349u, 5509u, 5669u, 5829u, 5989u, 6148u, 6308u,
    6467u, 6626u, 6784u, 6943u, 7101u, 7260u, 7418u, 7575u, 7733u, 7890u,
    8047u, 8204u, 8361u, 8517u, 8673u, 8829u, 8985u, 9140u, 9296u, 9450u,
    9605u, 9759u, 9914u, 10067u, 10221u, 10374u, 10527u, 10680u, 10832u, 10984u,
    11136u, 11287u, 11439u, 11590u, 11740u, 11890u, 12040u, 12190u, 12339u, 12488u,
    12637u, 12785u, 12933u, 13081u, 13228u, 13375u, 13522u, 13668u, 13814u, 13959u,
    14105u, 14249u, 14394u, 14538u, 14682u, 14825u, 14968u, 15111u, 15253u, 15395u,
    15537u, 15678u, 15819u, 15960u, 16100u, 16239u, 16379u, 16518u, 16656u, 16794u,
    16932u, 17069u, 17206u, 17343u, 17479u, 17615u, 17750u, 17885u, 18020u, 18154u,
    18288u, 18421u, 18554u, 18687u, 18819u, 18951u, 19083u, 19213u, 19344u, 19474u,
    19604u, 19733u, 19862u, 19991u, 20119u, 20247u, 20374u, 20501u, 20627u, 20753u,
    20879u, 21004u, 21129u, 21254u, 21378u, 21501u, 21624u, 21747u, 21870u, 21992u,
    22113u, 22234u, 22355u, 22475u, 22595u, 22714u, 22834u, 22952u, 23070u, 23188u,
    23306u, 23423u, 23539u, 23655u, 23771u, 23886u, 24001u, 24116u, 24230u, 24344u,
    24457u, 24570u, 24682u, 24795u, 24906u, 25017u, 25128u, 25239u, 25349u, 25459u,
    25568u, 25677u, 25785u, 25893u, 26001u, 26108u, 26215u, 26321u, 26427u, 26533u,
    26638u, 26743u, 26848u, 26952u, 27056u, 27159u, 27262u, 27364u, 27467u, 27568u,
    27670u, 27771u, 27871u, 27972u, 28072u, 28171u, 28270u, 28369u, 28467u, 28565u,
    28663u, 28760u, 28857u, 28953u, 29050u, 29145u, 29241u, 29336u, 29430u, 29525u,
    29619u, 29712u, 29805u, 29898u, 29991u, 30083u, 30175u, 30266u, 30357u, 30448u,
    30538u, 30628u, 30718u, 30807u, 30896u, 30985u, 31073u, 31161u, 31248u, 31336u,
    31423u, 31509u, 31595u, 31681u, 31767u, 31852u, 31937u, 32022u, 32106u, 32190u,
    32273u, 32357u, 32439u, 32522u, 32604u, 32686u, 32768u, 32768u,
};

}  // namespace detail

// ---------------------------------------------------------------------------
// Division
// ---------------------------------------------------------------------------
int32_t div_shl_round_sat(int32_t num, int32_t den, uint32_t k) {
  k &= 31;  // a larger k is caller misuse; masking keeps every shift defined
  if (num == 0) return 0;
  const bool neg = (num < 0) != (den < 0);
  const uint32_t a = num < 0 ? 0u - static_cast<uint32_t>(num) : static_cast<uint32_t>(num);  // <= 2^31
  const uint32_t d = den < 0 ? 0u - static_cast<uint32_t>(den) : static_cast<uint32_t>(den);  // <= 2^31
  const uint64_t n = uint64_t{a} << k;                                                         // <= 2^62
  // A quotient of 2^31 or more (or den = 0) saturates whichever way it rounds.
  if (n >= (uint64_t{d} << 31)) return neg ? INT32_MIN : INT32_MAX;

  // Q = n/d < 2^31. With mant <= 2^63/m < mant + 1 the estimate a*mant/2^(shift-k)
  // falls short of Q by a*(2^63/m - mant)/2^(shift-k) <= Q/mant < 1, so its
  // floor is floor(Q) or floor(Q) - 1: one correction step makes it exact.
  const Recip r = recip(d);
  uint32_t q = static_cast<uint32_t>(umul32x32_64(a, r.mant) >> (r.shift - k));
  uint64_t rem = n - umul32x32_64(q, d);  // in [0, 2d)
  if (rem >= d) {
    ++q;
    rem -= d;
  }
  // Ties toward +infinity: a positive quotient rounds a half up, a negative
  // one rounds the magnitude's half down.
  const uint64_t twice = 2 * rem;
  if (neg ? twice > d : twice >= d) ++q;  // q <= 2^31 now
  if (neg) return static_cast<int32_t>(0u - q);  // q = 2^31 is exactly INT32_MIN
  return q > static_cast<uint32_t>(INT32_MAX) ? INT32_MAX : static_cast<int32_t>(q);
}

int32_t div64_round_sat(int64_t num, int32_t den) {
  if (num == 0) return 0;
  const bool neg = (num < 0) != (den < 0);
  const uint64_t n = num < 0 ? 0u - static_cast<uint64_t>(num) : static_cast<uint64_t>(num);  // <= 2^63
  const uint32_t d = den < 0 ? 0u - static_cast<uint32_t>(den) : static_cast<uint32_t>(den);
  if (d == 0) return neg ? INT32_MIN : INT32_MAX;
  uint64_t q = n / d;
  const uint64_t twice = 2 * (n % d);
  if (neg ? twice > d : twice >= d) ++q;
  if (neg) return q > (uint64_t{1} << 31) ? INT32_MIN : static_cast<int32_t>(0u - static_cast<uint32_t>(q));
  return q > static_cast<uint64_t>(INT32_MAX) ? INT32_MAX : static_cast<int32_t>(q);
}

// ---------------------------------------------------------------------------
// Square roots
// ---------------------------------------------------------------------------
uint32_t isqrt32(uint32_t x) {
  if (x == 0) return 0;
  // xn = x * 4^k in [2^30, 2^32): sqrt(x) = sqrt(xn) / 2^k.
  const int k = clz32(x) >> 1;
  const uint32_t xn = x << (2 * k);
  uint32_t y = detail::kSqrtSeed.v[(xn >> 24) - detail::kSqrtSeedFirst];  // in [2^15, 2^16)
  // One Newton step. The seed's relative error e <= 2^-7.99 leaves
  // y in (sqrt(xn) - 1, sqrt(xn) + sqrt(xn) e^2 / 2] (< +0.51), so after the
  // shift y is floor(sqrt(x)) or off by one either way.
  y = (y + xn / y) >> 1;
  y >>= k;
  if (y > 0xFFFF) y = 0xFFFF;  // 65536 can appear for x near 2^32
  if (y * y > x) {
    --y;
  } else if (x - y * y > 2 * y) {  // (y + 1)^2 <= x
    ++y;
  }
  return y;
}

uint32_t isqrt64(uint64_t x) {
  if (x <= UINT32_MAX) return isqrt32(static_cast<uint32_t>(x));
  // xn = x * 4^k in [2^62, 2^64), k <= 15.
  const int k = clz64(x) >> 1;
  const uint64_t xn = x << (2 * k);
  // y0 = isqrt32(top half) * 2^16 <= sqrt(xn) < y0 + 2^16, and y0 >= 2^31.
  const uint32_t y0 = isqrt32(static_cast<uint32_t>(xn >> 32)) << 16;
  // Newton: y0 + r / (2 y0) with r = xn - y0^2 < 2^49 overshoots sqrt(xn) by
  // less than 1. The division is r * (2^63 / y0) / 2^64 with the exact
  // reciprocal; truncating r to its top 32 bits and the floors lose less
  // than 1.01, so y is floor(sqrt(xn)) or off by one either way.
  const uint64_t r = xn - umul32x32_64(y0, y0);
  const uint32_t c = static_cast<uint32_t>(umul32x32_64(static_cast<uint32_t>(r >> 17), recip_mant(y0)) >> 47);
  uint64_t y = uint64_t{y0} + c;
  if (y > UINT32_MAX) y = UINT32_MAX;
  uint32_t s = static_cast<uint32_t>(y) >> k;
  const uint64_t s2 = umul32x32_64(s, s);
  if (s2 > x) {
    --s;
  } else if (x - s2 > 2 * uint64_t{s}) {  // (s + 1)^2 <= x
    ++s;
  }
  return s;
}

uint64_t isqrt64_round(uint64_t x) {
  // sqrt(x) >= f + 1/2  <=>  x >= f^2 + f + 1/4  <=>  x - f^2 > f (integers).
  const uint32_t f = isqrt64(x);
  return uint64_t{f} + (x - umul32x32_64(f, f) > f);
}

Q16_16 sqrt_q16_16_floor(Q16_16 x) {
  if (x.raw() <= 0) return Q16_16{};
  // sqrt(raw / 2^16) * 2^16 = sqrt(raw * 2^16).
  return Q16_16::from_raw(static_cast<int32_t>(isqrt64(uint64_t(static_cast<uint32_t>(x.raw())) << 16)));
}

Q16_16 sqrt_q16_16_round(Q16_16 x) {
  if (x.raw() <= 0) return Q16_16{};
  return Q16_16::from_raw(static_cast<int32_t>(isqrt64_round(uint64_t(static_cast<uint32_t>(x.raw())) << 16)));
}

Q16_16 mat2_norm2_q16(Q16_16 a, Q16_16 b, Q16_16 c, Q16_16 d) {
  // sigma_max = (|(a+d, c-b)| + |(a-d, c+b)|) / 2 for [[a, b], [c, d]].
  int64_t u[4] = {int64_t{a.raw()} + d.raw(), int64_t{c.raw()} - b.raw(),
                  int64_t{a.raw()} - d.raw(), int64_t{c.raw()} + b.raw()};  // |u| <= 2^32
  // Squares of two terms must fit 2^64: with |u| > 2^31 drop one bit first
  // (floor), and the halving at the end is then skipped.
  bool halved = false;
  for (const int64_t v : u) halved |= v >= (int64_t{1} << 31) || v <= -(int64_t{1} << 31);
  if (halved) {
    for (int64_t& v : u) v >>= 1;
  }
  const uint64_t p1 = static_cast<uint64_t>(u[0] * u[0]) + static_cast<uint64_t>(u[1] * u[1]);
  const uint64_t p2 = static_cast<uint64_t>(u[2] * u[2]) + static_cast<uint64_t>(u[3] * u[3]);
  const uint64_t sum = isqrt64_round(p1) + isqrt64_round(p2);  // each rounded: <= 1/2 off
  const uint64_t sigma = halved ? sum : (sum + 1) >> 1;
  return Q16_16::from_raw(sigma > static_cast<uint64_t>(INT32_MAX) ? INT32_MAX : static_cast<int32_t>(sigma));
}

// ---------------------------------------------------------------------------
// Sine and cosine
// ---------------------------------------------------------------------------
namespace {
constexpr uint32_t kQuarterTurn32 = uint32_t{1} << 30;
constexpr int kSinIndexBits = 8;                       // 256 table intervals per quarter
constexpr int kSinFracBits32 = 30 - kSinIndexBits;     // angle bits below the index (22)
constexpr uint32_t kPiQ29 = 1686629713u;               // round(pi * 2^29)
constexpr uint32_t kOneSixthQ16 = 10923u;              // round(2^16 / 6)
}  // namespace

Q2_30 sin_q2_30(uint32_t angle) {
  const uint32_t quadrant = angle >> 30;
  uint32_t x = angle & (kQuarterTurn32 - 1);
  if (quadrant & 1) x = kQuarterTurn32 - x;  // sin(pi/2 + t) = sin(pi/2 - t); x = 2^30 is index 256
  const uint32_t i = x >> kSinFracBits32;
  const uint32_t f = x & ((uint32_t{1} << kSinFracBits32) - 1);
  const uint64_t s = detail::kSinQuarterQ1_31[i];        // sin at the table point, Q1.31
  const uint64_t c = detail::kSinQuarterQ1_31[256 - i];  // cos at the table point, Q1.31
  // Offset from the table point in radians: t = f * pi / 2^31 < 2^-7.34.
  // t in Q0.38 is f * pi * 2^7 = f * kPiQ29 / 2^22 (< 2^31); t^2 and t^3 in Q0.40.
  const uint64_t t = (uint64_t{f} * kPiQ29) >> 22;
  const uint64_t t2 = (t * t) >> 36;
  const uint64_t t3 = (t2 * t) >> 38;
  const uint64_t t3_6 = (t3 * kOneSixthQ16) >> 16;
  // sin(p + t) = s + c t - s t^2/2 - c t^3/6 + O(t^4/24 < 2^-34), summed in Q.62:
  // s << 31 (Q1.31 -> Q.62), c*t is Q.69, s*t2 is Q.71 (and /2), c*t3/6 is Q.71.
  const int64_t acc = static_cast<int64_t>((s << 31) + ((c * t) >> 7)) - static_cast<int64_t>((s * t2) >> 10) -
                      static_cast<int64_t>((c * t3_6) >> 9);
  const int32_t mag = static_cast<int32_t>((acc + (int64_t{1} << 31)) >> 32);  // Q.62 -> Q2.30, ties up
  return Q2_30::from_raw(quadrant & 2 ? -mag : mag);
}

Q2_30 cos_q2_30(uint32_t angle) { return sin_q2_30(angle + kQuarterTurn32); }

Q1_15 sin_q1_15(uint16_t angle) {
  constexpr uint32_t kQuarterTurn16 = uint32_t{1} << 14;
  constexpr int kFracBits16 = 14 - kSinIndexBits;  // 6 bits interpolate between table points
  const uint32_t quadrant = uint32_t{angle} >> 14;
  uint32_t x = angle & (kQuarterTurn16 - 1);
  if (quadrant & 1) x = kQuarterTurn16 - x;
  const uint32_t i = x >> kFracBits16;
  const int32_t f = static_cast<int32_t>(x & ((uint32_t{1} << kFracBits16) - 1));
  const uint32_t s0 = detail::kSinQuarterQ1_31[i];
  const int32_t step = static_cast<int32_t>(detail::kSinQuarterQ1_31[i + 1] - s0);  // |step| < 2^24
  const uint32_t v = s0 + static_cast<uint32_t>((step * f) >> kFracBits16);        // Q1.31, <= 2^31
  // Q1.31 -> Q1.15 rounded; 1.0 (32768) is not representable and clamps.
  int32_t mag = static_cast<int32_t>((v + (uint32_t{1} << 15)) >> 16);
  if (mag > INT16_MAX) mag = INT16_MAX;
  return Q1_15::from_raw(static_cast<int16_t>(quadrant & 2 ? -mag : mag));
}

Q1_15 cos_q1_15(uint16_t angle) { return sin_q1_15(static_cast<uint16_t>(angle + (1u << 14))); }

// ---------------------------------------------------------------------------
// atan2
// ---------------------------------------------------------------------------
uint16_t atan2_angle16(int32_t y, int32_t x) {
  if (x == 0 && y == 0) return 0;
  const uint32_t ax = x < 0 ? 0u - static_cast<uint32_t>(x) : static_cast<uint32_t>(x);
  const uint32_t ay = y < 0 ? 0u - static_cast<uint32_t>(y) : static_cast<uint32_t>(y);
  // Reduce to the first octant: atan(lo / hi) with lo <= hi, hi > 0.
  const bool swap = ay > ax;
  const uint32_t lo = swap ? ax : ay;
  const uint32_t hi = swap ? ay : ax;
  // z = lo / hi in Q0.24 from the exact reciprocal (floor or one below).
  constexpr uint32_t kRatioFracBits = 24;
  const Recip r = recip(hi);
  const uint32_t z = static_cast<uint32_t>(umul32x32_64(lo, r.mant) >> (r.shift - kRatioFracBits));  // <= 2^24
  // Table index: top 8 fraction bits of z; 16 bits interpolate.
  const uint32_t i = z >> 16;
  const int32_t f = static_cast<int32_t>(z & 0xFFFF);
  const int32_t step = int32_t{detail::kAtanTurnsQ18[i + 1]} - int32_t{detail::kAtanTurnsQ18[i]};  // < 2^8
  // phi in 2^-32 turn: table (2^-18) << 14, step * f is in 2^-34.
  uint32_t phi = (uint32_t{detail::kAtanTurnsQ18[i]} << 14) + static_cast<uint32_t>((step * f) >> 2);
  constexpr uint32_t kQuarter = uint32_t{1} << 30;
  constexpr uint32_t kHalf = uint32_t{1} << 31;
  if (swap) phi = kQuarter - phi;  // atan(hi/lo) = pi/2 - atan(lo/hi)
  uint32_t theta;
  if (x >= 0) {
    theta = y >= 0 ? phi : 0u - phi;
  } else {
    theta = y >= 0 ? kHalf - phi : kHalf + phi;
  }
  // 2^-32 turn -> 2^-16 turn, ties up, modulo one turn.
  return static_cast<uint16_t>((theta + (uint32_t{1} << 15)) >> 16);
}

}  // namespace vds
