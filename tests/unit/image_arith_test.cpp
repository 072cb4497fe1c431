// The image decoder's inlined range decoder (vds::image_model::RangeDecoder)
// against the entropy core's vds::ArithDecoder: the same bins, the same
// latched status and the same finish() verdict on encoder output, on
// truncated and extended output and on random bytes; the same for the
// decoder's packed contexts (bit(PackedContext&)), state included.
#include <gtest/gtest.h>

#include <vector>

#include "vds/arith.h"
#include "vds/enc/arith_encoder.h"
#include "vds/image_model.h"
#include "xorshift.h"

namespace {

using vds::ArithContext;
using vds::Status;
using vds::image_model::RangeDecoder;

using Rng = vds::test::Xorshift32;

// What the image codec's contexts look like: past the warm-up, default shifts.
ArithContext warm(uint32_t p0_q15) {
  ArithContext c = vds::arith_context(vds::kArithDefaultFastShift, vds::kArithDefaultSlowShift, p0_q15);
  c.count = vds::kArithWarmupDone;
  return c;
}

// One operation of a script: a context bin, a bypass bin or an order-k
// Exp-Golomb value.
struct Op {
  int kind;  // 0 context, 1 bypass, 2 Exp-Golomb
  int ctx;
  int k;
};

// Runs the script through both decoders and compares everything.
void compare(const std::vector<uint8_t>& bytes, const std::vector<Op>& ops, const std::vector<ArithContext>& init) {
  std::vector<ArithContext> ca = init, cb = init;
  // The client decoder's packed contexts (both estimates in one word).
  std::vector<vds::image_model::PackedContext> cp;
  for (const ArithContext& c : init) cp.push_back(vds::image_model::pack_context(c));
  vds::ArithDecoder a;
  RangeDecoder b, p;
  ASSERT_EQ(a.init(bytes.data(), bytes.size()), b.init(bytes.data(), static_cast<uint32_t>(bytes.size())));
  ASSERT_EQ(p.init(bytes.data(), static_cast<uint32_t>(bytes.size())), b.status);
  for (size_t i = 0; i < ops.size(); ++i) {
    const Op& op = ops[i];
    if (op.kind == 0) {
      const int bin = a.decode_bit(ca[op.ctx]);
      ASSERT_EQ(bin, b.bit(cb[op.ctx])) << "bin " << i;
      ASSERT_EQ(bin, p.bit(cp[op.ctx])) << "packed bin " << i;
      ASSERT_EQ(ca[op.ctx].p0_fast, cb[op.ctx].p0_fast);
      ASSERT_EQ(ca[op.ctx].p0_slow, cb[op.ctx].p0_slow);
      ASSERT_EQ(cp[op.ctx], vds::image_model::pack_context(ca[op.ctx])) << "packed state " << i;
    } else if (op.kind == 1) {
      const int bin = a.decode_bypass();
      ASSERT_EQ(bin, b.bypass()) << "bin " << i;
      ASSERT_EQ(bin, p.bypass()) << "bin " << i;
    } else {
      const uint32_t v = a.decode_exp_golomb(nullptr, 0, op.k);
      ASSERT_EQ(v, b.exp_golomb(op.k)) << "value " << i;
      ASSERT_EQ(v, p.exp_golomb(op.k)) << "value " << i;
    }
    b.check_end();  // the decode loop's check point
    p.check_end();
    ASSERT_EQ(a.status(), b.status) << "after op " << i;
    ASSERT_EQ(a.status(), p.status) << "after op " << i;
  }
  const Status done = a.finish();
  ASSERT_EQ(done, b.finish());
  ASSERT_EQ(done, p.finish());
}

TEST(ImageArith, MatchesArithDecoderOnEncoderOutput) {
  Rng r{12345};
  for (int trial = 0; trial < 200; ++trial) {
    const int nctx = 1 + static_cast<int>(r.next() % 8);
    std::vector<ArithContext> init;
    for (int c = 0; c < nctx; ++c) init.push_back(warm(1 + r.next() % 32767));
    std::vector<ArithContext> enc_ctx = init;
    vds::enc::ArithEncoder e;
    std::vector<Op> ops;
    const int n = static_cast<int>(r.next() % 400);
    for (int i = 0; i < n; ++i) {
      const uint32_t kind = r.next() % 10;
      if (kind < 7) {
        const int c = static_cast<int>(r.next() % nctx);
        // Skewed bins, as real contexts see them.
        const int bin = (r.next() % 100) < static_cast<uint32_t>(c * 12) ? 1 : 0;
        e.encode_bit(enc_ctx[c], bin);
        ops.push_back({0, c, 0});
      } else if (kind < 9) {
        e.encode_bypass(static_cast<int>(r.next() & 1));
        ops.push_back({1, 0, 0});
      } else {
        const int k = static_cast<int>(r.next() % 5);
        e.encode_exp_golomb(nullptr, 0, r.next() % 300, k);
        ops.push_back({2, 0, k});
      }
    }
    const std::vector<uint8_t> bytes = e.finish();
    compare(bytes, ops, init);
    // Cut short: both latch truncated at the same bin.
    if (!bytes.empty()) {
      std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(r.next() % bytes.size()));
      compare(cut, ops, init);
    }
    // A trailing byte: both report it at finish().
    std::vector<uint8_t> longer = bytes;
    longer.push_back(static_cast<uint8_t>(r.next()));
    compare(longer, ops, init);
  }
}

TEST(ImageArith, MatchesArithDecoderOnRandomBytes) {
  Rng r{777};
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> bytes(r.next() % 64);
    for (auto& b : bytes) b = static_cast<uint8_t>(r.next());
    if (trial % 7 == 0 && bytes.size() >= 4) bytes[0] = bytes[1] = bytes[2] = bytes[3] = 0xFF;  // malformed start
    std::vector<ArithContext> init = {warm(16384), warm(30000), warm(100)};
    std::vector<Op> ops;
    for (int i = 0; i < 300; ++i) {
      const uint32_t kind = r.next() % 12;
      // Long Exp-Golomb prefixes reach the malformed rule on random bytes.
      ops.push_back(kind < 8 ? Op{0, static_cast<int>(r.next() % 3), 0}
                             : (kind < 11 ? Op{1, 0, 0} : Op{2, 0, static_cast<int>(r.next() % 31)}));
    }
    compare(bytes, ops, init);
  }
}

// The client decoder's level loop relies on a zero PackedContext being a
// free "always 1" bin (no sig bin is coded where no zeros are left): the
// bin is 1, and range, code, the read position and the context are unchanged.
TEST(ImageArith, ZeroPackedContextIsAFreeOne) {
  Rng r{4242};
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<uint8_t> bytes(8 + r.next() % 64);
    for (auto& b : bytes) b = static_cast<uint8_t>(r.next());
    bytes[0] &= 0x7F;  // a valid start
    RangeDecoder d;
    ASSERT_EQ(d.init(bytes.data(), static_cast<uint32_t>(bytes.size())), Status::ok);
    vds::image_model::PackedContext live = 0x40004000u;  // p0 = 0.5 in both halves
    const int before = static_cast<int>(r.next() % 40);
    for (int i = 0; i < before; ++i) d.bit(live);
    const RangeDecoder saved = d;
    vds::image_model::PackedContext zero = 0;
    for (int i = 0; i < 5; ++i) {
      EXPECT_EQ(d.bit(zero), 1);
      EXPECT_EQ(zero, 0u);
    }
    EXPECT_EQ(d.range, saved.range);
    EXPECT_EQ(d.code, saved.code);
    EXPECT_EQ(d.ptr, saved.ptr);
    EXPECT_EQ(d.past, saved.past);
  }
}

}  // namespace
