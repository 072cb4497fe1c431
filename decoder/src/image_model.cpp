// vds image codec: starting state of the adaptive contexts (image_model.h),
// shared by the client decoder and the host encoder. The starting
// probabilities were trained on textures outside the benchmark set
// (bench/src/texture_train.cpp regenerates image_model_init.inc).
#include "vds/image_model.h"

namespace vds::image_model {

namespace {

// Per context, in declaration order: the probability of a 0 bin (in 1/256)
// at quantiser index kInitIndexLo and kInitIndexHi; other indices
// interpolate linearly (and hold the end values beyond them).
constexpr int kInitIndexLo = 32;
constexpr int kInitIndexHi = 192;
constexpr uint8_t kInit[kContextCount][2] = {
#include "image_model_init.inc"
};

// Init probabilities are in 1/256; contexts hold Q15: x * 128 + 64 is the
// centre of the 1/256 interval.
constexpr int kInitToQ15Shift = kArithProbShift - 8;
constexpr uint32_t kInitHalfStep = 1u << (kInitToQ15Shift - 1);

template <typename Ctx, typename F>
void for_each(ContextsOf<Ctx>& c, F&& f) {
  for (ClassContextsOf<Ctx>& k : c.cls) {
    for (auto& x : k.cbf) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& x : k.dc_zero) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& x : k.dc_gt1) f(x, &k == &c.cls[0] ? 0 : 1);
    f(k.dc_gt2, &k == &c.cls[0] ? 0 : 1);
    for (auto& row : k.nz_prefix)
      for (auto& x : row) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& x : k.nz_suffix) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& row : k.sig)
      for (auto& x : row) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& row : k.gt1)
      for (auto& x : row) f(x, &k == &c.cls[0] ? 0 : 1);
    for (auto& row : k.gt2)
      for (auto& x : row) f(x, &k == &c.cls[0] ? 0 : 1);
  }
  for (auto& x : c.region) f(x, 0);
}

// The starting state of context i of class cls.
ArithContext start_context(size_t i, int cls, int quant_luma, int quant_chroma) {
  int q = cls == 0 ? quant_luma : quant_chroma;
  q = q < kInitIndexLo ? kInitIndexLo : (q > kInitIndexHi ? kInitIndexHi : q);
  const int lo = kInit[i][0], hi = kInit[i][1];
  const int p = lo + ((hi - lo) * (q - kInitIndexLo)) / (kInitIndexHi - kInitIndexLo);
  ArithContext x = arith_context(kArithDefaultFastShift, kArithDefaultSlowShift,
                                 (static_cast<uint32_t>(p) << kInitToQ15Shift) + kInitHalfStep);
  // Trained starting points make the warm-up (fast learning from 0.5)
  // unnecessary; skipping it also spares every bin its bookkeeping.
  x.count = kArithWarmupDone;
  return x;
}

}  // namespace

void init_contexts(Contexts& c, int quant_luma, int quant_chroma) {
  size_t i = 0;
  for_each(c, [&](ArithContext& x, int cls) { x = start_context(i++, cls, quant_luma, quant_chroma); });
}

void init_contexts(PackedContexts& c, int quant_luma, int quant_chroma) {
  size_t i = 0;
  for_each(c, [&](PackedContext& x, int cls) { x = pack_context(start_context(i++, cls, quant_luma, quant_chroma)); });
}

ArithContext& context_at(Contexts& c, size_t i) {
  ArithContext* found = &c.region[0];
  size_t n = 0;
  for_each(c, [&](ArithContext& x, int) {
    if (n++ == i) found = &x;
  });
  return *found;
}

static_assert(sizeof(Contexts) % sizeof(ArithContext) == 0, "Contexts holds only ArithContext");
static_assert(sizeof(PackedContexts) == kContextCount * sizeof(PackedContext), "the same contexts, packed");

}  // namespace vds::image_model
