// Fuzzes the range decoder: raw bytes decoded with a mix of context bins,
// bypass bins and every binarisation until the end rule trips; and a round
// trip (input read as a list of values -> host encoder -> decoder) that
// traps on any mismatch or a finish() that is not ok.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "vds/arith.h"
#include "vds/enc/arith_encoder.h"

namespace {

constexpr int kContexts = 16;
constexpr size_t kMaxOps = 1u << 15;

void check(bool ok) {
  if (!ok) __builtin_trap();
}

std::unique_ptr<uint8_t[]> exact_copy(const uint8_t* p, size_t n) {
  std::unique_ptr<uint8_t[]> copy(new uint8_t[n]);
  if (n) std::memcpy(copy.get(), p, n);
  return copy;
}

// Mode 0: the first byte gives the length of an op script, the rest is the stream.
void raw_decode(const uint8_t* data, size_t size) {
  if (size < 1) return;
  size_t script_len = 1 + data[0] % 32;
  if (script_len > size - 1) script_len = size - 1;
  const uint8_t* script = data + 1;
  if (script_len == 0) return;
  const size_t n = size - 1 - script_len;
  auto copy = exact_copy(data + 1 + script_len, n);
  vds::ArithContext ctx[kContexts];
  vds::arith_init_contexts(ctx, kContexts);
  vds::ArithDecoder dec;
  dec.init(copy.get(), n);
  for (size_t i = 0; i < kMaxOps && dec.ok(); ++i) {
    const uint8_t op = script[i % script_len];
    vds::ArithContext* c = ctx + (op >> 4);
    const int nctx = kContexts - (op >> 4);
    switch (op & 7) {
      case 0: check(dec.decode_bit(*c) <= 1); break;
      case 1: check(dec.decode_bypass() <= 1); break;
      case 2: {
        const int bits = op >> 3;  // 0..31
        check(dec.decode_bits_bypass(bits) < (uint64_t{1} << bits));
        break;
      }
      case 3: check(dec.decode_unary(c, nctx, op) <= op); break;
      case 4: dec.decode_exp_golomb(c, (op >> 3) & 1 ? 0 : nctx, op % 31); break;
      case 5: dec.decode_ueg(c, nctx, op >> 4, op & 3); break;
      case 6: {
        const int32_t v = dec.decode_signed(c[0], c + 1, nctx - 1, op >> 3, (op >> 6) & 3);
        check(v != INT32_MIN);
        break;
      }
      default: dec.decode_bits_bypass(32); break;
    }
  }
  // Running out of operations is fine; an error is always one of these.
  const vds::Status st = dec.status();
  check(st == vds::Status::ok || st == vds::Status::truncated || st == vds::Status::malformed);
}

struct Item {
  uint8_t kind;
  uint8_t arg;
  uint32_t value;
};

uint32_t take32(const uint8_t*& p, const uint8_t* end) {
  uint32_t v = 0;
  for (int i = 0; i < 4 && p < end; ++i) v = v << 8 | *p++;
  return v;
}

// Mode 1: round trip of a value list.
void round_trip(const uint8_t* data, size_t size) {
  const uint8_t* p = data;
  const uint8_t* end = data + size;
  std::vector<Item> items;
  while (p < end && items.size() < 4096) {
    Item it{};
    it.kind = static_cast<uint8_t>(*p++ % 7);
    it.arg = p < end ? *p++ : 0;
    const uint32_t raw = take32(p, end);
    // Small values mostly, so the context bins adapt; the top byte picks a scale.
    it.value = raw >> (raw >> 27);
    items.push_back(it);
  }
  auto limits = [](const Item& it, uint32_t& value) {
    switch (it.kind) {
      case 0:
      case 1: value &= 1; break;
      case 2: {
        const int n = it.arg % 33;
        if (n < 32) value &= (1u << n) - 1;
        break;
      }
      case 3:
        if (value > it.arg) value = it.arg;
        break;
      case 4: {
        const uint64_t lim = (uint64_t{1} << 32) - (uint64_t{1} << (it.arg % 31));
        if (value >= lim) value = 0;
        break;
      }
      case 5: {
        const uint32_t cut = it.arg >> 4;
        const uint64_t lim = (uint64_t{1} << 32) - (uint64_t{1} << (it.arg & 3));
        if (value >= cut && value - cut >= lim) value = cut;
        break;
      }
      default: if (value == 0x80000000u) value = 0; break;
    }
  };
  for (Item& it : items) limits(it, it.value);

  vds::ArithContext ectx[kContexts];
  vds::arith_init_contexts(ectx, kContexts / 2);
  vds::arith_init_contexts(ectx + kContexts / 2, kContexts / 2, 3, 9, 4000);
  vds::enc::ArithEncoder enc;
  for (const Item& it : items) {
    vds::ArithContext* c = ectx + (it.arg & 7);
    const int nctx = (it.arg >> 3) & 7;
    switch (it.kind) {
      case 0: enc.encode_bit(*c, static_cast<int>(it.value)); break;
      case 1: enc.encode_bypass(static_cast<int>(it.value)); break;
      case 2: enc.encode_bits_bypass(it.value, it.arg % 33); break;
      case 3: enc.encode_unary(c, nctx, it.value, it.arg); break;
      case 4: enc.encode_exp_golomb(c, nctx, it.value, it.arg % 31); break;
      case 5: enc.encode_ueg(c, nctx, it.value, it.arg >> 4, it.arg & 3); break;
      default: enc.encode_signed(c[0], c + 1, nctx, static_cast<int32_t>(it.value), it.arg >> 5, it.arg & 3); break;
    }
  }
  const size_t predicted = enc.finished_size();
  const std::vector<uint8_t> bytes = enc.finish();
  check(bytes.size() == predicted);

  auto copy = exact_copy(bytes.data(), bytes.size());
  vds::ArithContext dctx[kContexts];
  vds::arith_init_contexts(dctx, kContexts / 2);
  vds::arith_init_contexts(dctx + kContexts / 2, kContexts / 2, 3, 9, 4000);
  vds::ArithDecoder dec;
  check(dec.init(copy.get(), bytes.size()) == vds::Status::ok);
  for (const Item& it : items) {
    vds::ArithContext* c = dctx + (it.arg & 7);
    const int nctx = (it.arg >> 3) & 7;
    uint32_t v = 0;
    switch (it.kind) {
      case 0: v = static_cast<uint32_t>(dec.decode_bit(*c)); break;
      case 1: v = static_cast<uint32_t>(dec.decode_bypass()); break;
      case 2: v = dec.decode_bits_bypass(it.arg % 33); break;
      case 3: v = dec.decode_unary(c, nctx, it.arg); break;
      case 4: v = dec.decode_exp_golomb(c, nctx, it.arg % 31); break;
      case 5: v = dec.decode_ueg(c, nctx, it.arg >> 4, it.arg & 3); break;
      default: v = static_cast<uint32_t>(dec.decode_signed(c[0], c + 1, nctx, it.arg >> 5, it.arg & 3)); break;
    }
    check(v == it.value);
  }
  check(dec.finish() == vds::Status::ok);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  if (data[0] & 1)
    round_trip(data + 1, size - 1);
  else
    raw_decode(data + 1, size - 1);
  return 0;
}
