// Entropy-coding throughput on the host: context-coded and bypass bins of the
// range decoder and canonical Huffman symbols (lookup path and long codes).
// Each decode loop is its own non-inlined function so callgrind can count it
// alone (bench/results/entropy.md has the commands).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "vds/arena.h"
#include "vds/arith.h"
#include "vds/bitreader.h"
#include "vds/enc/arith_encoder.h"
#include "vds/enc/bitwriter.h"
#include "vds/enc/huffman_build.h"
#include "vds/huffman.h"

namespace {

constexpr int kContexts = 16;
constexpr size_t kBins = 1000000;
constexpr size_t kSymbols = 1000000;

// Probability of a 1 for context c: from 0.02 to 0.5, like significance and
// level bins of a transform codec.
double p_one(int c) { return 0.02 + 0.03 * c; }

__attribute__((noinline)) uint32_t bench_arith_context_decode(const std::vector<uint8_t>& bytes, size_t n) {
  vds::ArithContext ctx[kContexts];
  vds::arith_init_contexts(ctx, kContexts);
  vds::ArithDecoder dec;
  dec.init(bytes.data(), bytes.size());
  uint32_t sum = 0;
  for (size_t i = 0; i < n; ++i) sum += static_cast<uint32_t>(dec.decode_bit(ctx[i % kContexts]));
  return dec.finish() == vds::Status::ok ? sum : 0xFFFFFFFFu;
}

__attribute__((noinline)) uint32_t bench_arith_bypass_decode(const std::vector<uint8_t>& bytes, size_t n) {
  vds::ArithDecoder dec;
  dec.init(bytes.data(), bytes.size());
  uint32_t sum = 0;
  for (size_t i = 0; i < n; ++i) sum += static_cast<uint32_t>(dec.decode_bypass());
  return dec.finish() == vds::Status::ok ? sum : 0xFFFFFFFFu;
}

inline uint32_t huffman_decode_loop(const vds::HuffmanTable& t, const std::vector<uint8_t>& bytes, size_t n) {
  vds::BitReader br(bytes.data(), bytes.size());
  uint32_t sum = 0;
  for (size_t i = 0; i < n; ++i) sum += static_cast<uint32_t>(t.decode(br));
  return br.ok() ? sum : 0xFFFFFFFFu;
}

// One function per alphabet so callgrind can count each alone.
__attribute__((noinline)) uint32_t bench_huffman_skewed_decode(const vds::HuffmanTable& t,
                                                               const std::vector<uint8_t>& bytes, size_t n) {
  return huffman_decode_loop(t, bytes, n);
}
__attribute__((noinline)) uint32_t bench_huffman_zipf_decode(const vds::HuffmanTable& t,
                                                             const std::vector<uint8_t>& bytes, size_t n) {
  return huffman_decode_loop(t, bytes, n);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct HuffCase {
  const char* name;
  std::vector<uint64_t> freqs;
};

}  // namespace

int main() {
  std::mt19937 rng(1);

  // --- Range coder: context bins ---
  std::vector<int> bins(kBins);
  double entropy = 0;
  for (size_t i = 0; i < kBins; ++i) {
    const double p = p_one(static_cast<int>(i % kContexts));
    bins[i] = std::bernoulli_distribution(p)(rng);
    entropy += -(p * std::log2(p) + (1 - p) * std::log2(1 - p));
  }
  vds::ArithContext ectx[kContexts];
  vds::arith_init_contexts(ectx, kContexts);
  vds::enc::ArithEncoder enc;
  auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < kBins; ++i) enc.encode_bit(ectx[i % kContexts], bins[i]);
  const std::vector<uint8_t> ctx_stream = enc.finish();
  const double t_enc = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  const uint32_t ones = bench_arith_context_decode(ctx_stream, kBins);
  const double t_dec = seconds_since(t0);
  uint32_t expect = 0;
  for (int b : bins) expect += static_cast<uint32_t>(b);
  std::printf("arith context bins: %zu bins, %zu bytes, %.4f bits/bin (entropy %.4f), encode %.2f ns/bin, decode %.2f ns/bin%s\n",
              kBins, ctx_stream.size(), 8.0 * static_cast<double>(ctx_stream.size()) / kBins, entropy / kBins,
              1e9 * t_enc / kBins, 1e9 * t_dec / kBins, ones == expect ? "" : "  MISMATCH");

  // --- Range coder: bypass bins ---
  for (size_t i = 0; i < kBins; ++i) enc.encode_bypass(bins[i] ^ static_cast<int>(i & 1));
  const std::vector<uint8_t> byp_stream = enc.finish();
  t0 = std::chrono::steady_clock::now();
  const uint32_t byp = bench_arith_bypass_decode(byp_stream, kBins);
  std::printf("arith bypass bins: %zu bins, %zu bytes, decode %.2f ns/bin%s\n", kBins, byp_stream.size(),
              1e9 * seconds_since(t0) / kBins, byp == 0xFFFFFFFFu ? "  MISMATCH" : "");

  // --- Huffman: a JPEG-AC-like skewed 256-symbol alphabet (almost all codes
  // resolved by the lookup) and a Zipf one (many codes longer than the
  // lookup) ---
  std::vector<HuffCase> cases;
  {
    HuffCase c{"huffman skewed-256", std::vector<uint64_t>(256)};
    for (size_t s = 0; s < 256; ++s) c.freqs[s] = 1 + static_cast<uint64_t>(100000.0 * std::exp(-0.08 * s));
    cases.push_back(c);
    // Zipf over 2048 symbols: most codes are 10..16 bits.
    HuffCase f{"huffman zipf-2048", std::vector<uint64_t>(2048)};
    for (size_t s = 0; s < f.freqs.size(); ++s) f.freqs[s] = 1 + 1000000 / (s + 1);
    cases.push_back(f);
  }
  for (const HuffCase& hc : cases) {
    const vds::enc::CanonicalCode code = vds::enc::huffman_build(hc.freqs, 16);
    std::discrete_distribution<size_t> pick(hc.freqs.begin(), hc.freqs.end());
    vds::enc::BitWriter bw;
    uint64_t long_codes = 0;
    std::vector<uint16_t> syms(kSymbols);
    for (auto& s : syms) {
      s = static_cast<uint16_t>(pick(rng));
      code.write(bw, s);
      long_codes += code.lengths[s] > vds::HuffmanTable::kLookupBits;
    }
    const size_t bits = bw.bit_count();
    const std::vector<uint8_t> stream = bw.finish();
    std::vector<uint8_t> work(vds::HuffmanTable::workspace_bytes(hc.freqs.size()));
    vds::Arena arena(work.data(), work.size());
    vds::HuffmanTable t;
    t.reserve(arena, hc.freqs.size());
    t.build_from_lengths(code.lengths.data(), code.lengths.size());
    t0 = std::chrono::steady_clock::now();
    const uint32_t sum = hc.freqs.size() == 256 ? bench_huffman_skewed_decode(t, stream, kSymbols)
                                                : bench_huffman_zipf_decode(t, stream, kSymbols);
    const double t_h = seconds_since(t0);
    uint32_t want = 0;
    for (uint16_t s : syms) want += s;
    std::printf("%s: %zu symbols, %.3f bits/symbol, %.1f%% longer than %d bits, decode %.2f ns/symbol%s\n", hc.name,
                kSymbols, static_cast<double>(bits) / kSymbols, 100.0 * static_cast<double>(long_codes) / kSymbols,
                vds::HuffmanTable::kLookupBits, 1e9 * t_h / kSymbols, sum == want ? "" : "  MISMATCH");
  }
  return 0;
}
