// vds client library: the walkthrough stream's chunks and cameras (vds/walk.h).
#include "vds/walk.h"

#include "vds/bytes.h"
#include "vds/walk_geometry.h"

namespace vds {

Status walk_camera(const StreamHeader& h, const WalkPose& pose, Camera* out) {
  // 2^-16 turn to 2^-32 turn.
  const uint32_t yaw = static_cast<uint32_t>(pose.yaw) << 16, pitch = static_cast<uint32_t>(pose.pitch) << 16;
  const Q2_30 cy = cos_q2_30(yaw), sy = sin_q2_30(yaw), cp = cos_q2_30(pitch), sp = sin_q2_30(pitch);
  Camera c{};
  // Rows: right (sin y, -cos y, 0), down (sin p cos y, sin p sin y, -cos p),
  // forward (cos p cos y, cos p sin y, sin p).
  c.rotation.m[0][0] = sy;
  c.rotation.m[0][1] = Q2_30::from_raw(-cy.raw());
  c.rotation.m[0][2] = Q2_30::from_raw(0);
  c.rotation.m[1][0] = mul_round<Q2_30>(sp, cy);
  c.rotation.m[1][1] = mul_round<Q2_30>(sp, sy);
  c.rotation.m[1][2] = Q2_30::from_raw(-cp.raw());
  c.rotation.m[2][0] = mul_round<Q2_30>(cp, cy);
  c.rotation.m[2][1] = mul_round<Q2_30>(cp, sy);
  c.rotation.m[2][2] = sp;
  c.position = pose.position;
  c.fx = Q16_16::from_raw(h.focal_x_q16);
  c.fy = Q16_16::from_raw(h.focal_y_q16);
  c.cx = Q16_16::from_raw(h.center_x_q16);
  c.cy = Q16_16::from_raw(h.center_y_q16);
  c.near_z = Q16_16::from_raw(h.near_q16);
  c.far_z = Q16_16::from_raw(h.far_q16);
  if (validate_camera(c) != Status::ok) return Status::invalid_argument;
  *out = c;
  return Status::ok;
}

Status walk_view_camera(const StreamHeader& h, const WalkParams& w, const WalkPose& pose, Camera* out, uint8_t zoom) {
  if (zoom < kWalkZoomUnit || zoom > kWalkMaxZoom) return Status::malformed;
  const int64_t focal = static_cast<int64_t>(w.view_focal_q16) * zoom / kWalkZoomUnit;
  if (focal <= 0 || focal > INT32_MAX) return Status::malformed;
  StreamHeader v = h;
  v.focal_x_q16 = v.focal_y_q16 = static_cast<int32_t>(focal);
  v.center_x_q16 = static_cast<int32_t>(w.view_width) << 15;
  v.center_y_q16 = static_cast<int32_t>(w.view_height) << 15;
  return walk_camera(v, pose, out);
}

Status walk_params_from_bytes(const uint8_t* p, uint32_t size, WalkParams* out) {
  if (size != kWalkParamsBytes) return Status::malformed;
  WalkParams w;
  w.slots = load_le16(p);
  w.views = p[2];
  w.quantum_raw = load_le32s(p + 4);
  w.view_focal_q16 = load_le32s(p + 8);
  w.frames_per_record = p[3];
  w.view_width = load_le16(p + 12);
  w.view_height = load_le16(p + 14);
  w.rate_bytes = load_le32(p + 16);
  w.buffer_bytes = load_le32(p + 20);
  w.preroll_ms = load_le32(p + 24);
  const bool timed = w.rate_bytes != 0;
  if ((!timed && (w.buffer_bytes != 0 || w.preroll_ms != 0)) || w.preroll_ms > kWalkMaxPrerollMs) return Status::malformed;
  if (w.view_focal_q16 < (kCameraMinFocalPx << 16) || w.view_focal_q16 > (kCameraMaxFocalPx << 16) || w.slots == 0 ||
      w.views == 0 || w.views > kWalkMaxViews || w.frames_per_record == 0 || w.frames_per_record > kWalkMaxFramesPerRecord ||
      !walk_quantum_valid(w.quantum_raw) || w.view_width < 16 ||
      w.view_height < 16)
    return Status::malformed;
  *out = w;
  return Status::ok;
}

void walk_params_to_bytes(const WalkParams& w, uint8_t out[kWalkParamsBytes]) {
  store_le16(out, w.slots);
  out[2] = w.views;
  out[3] = w.frames_per_record;
  store_le32(out + 4, static_cast<uint32_t>(w.quantum_raw));
  store_le32(out + 8, static_cast<uint32_t>(w.view_focal_q16));
  store_le16(out + 12, w.view_width);
  store_le16(out + 14, w.view_height);
  store_le32(out + 16, w.rate_bytes);
  store_le32(out + 20, w.buffer_bytes);
  store_le32(out + 24, w.preroll_ms);
}

Status walk_view_from_bytes(const uint8_t* p, uint32_t size, WalkViewUpdate* out) {
  if (size != kWalkViewBytes && size != kWalkViewMaxBytes) return Status::malformed;
  out->zoom = size == kWalkViewMaxBytes ? p[17] : kWalkZoomUnit;
  if (size == kWalkViewMaxBytes && (out->zoom <= kWalkZoomUnit || out->zoom > kWalkMaxZoom)) return Status::malformed;
  out->slot = p[0] & static_cast<uint8_t>(~kWalkViewPredict);
  out->predict = (p[0] & kWalkViewPredict) != 0;
  out->pose.position = {Q16_16::from_raw(load_le32s(p + 1)), Q16_16::from_raw(load_le32s(p + 5)), Q16_16::from_raw(load_le32s(p + 9))};
  out->pose.yaw = load_le16(p + 13);
  out->pose.pitch = load_le16(p + 15);
  return Status::ok;
}

uint32_t walk_view_to_bytes(const WalkViewUpdate& u, uint8_t out[kWalkViewMaxBytes]) {
  out[0] = static_cast<uint8_t>(u.slot | (u.predict ? kWalkViewPredict : 0));
  store_le32(out + 1, static_cast<uint32_t>(u.pose.position.x.raw()));
  store_le32(out + 5, static_cast<uint32_t>(u.pose.position.y.raw()));
  store_le32(out + 9, static_cast<uint32_t>(u.pose.position.z.raw()));
  store_le16(out + 13, u.pose.yaw);
  store_le16(out + 15, u.pose.pitch);
  if (u.zoom == kWalkZoomUnit) return kWalkViewBytes;
  out[17] = u.zoom;
  return kWalkViewMaxBytes;
}

void WalkFrameState::reset() {
  arith_init_contexts(&zero[0], 5);
  arith_init_contexts(&mag[0][0], 5 * 6);
  arith_init_contexts(&same_view[0], 6);
  arith_init_contexts(&record_frames[0], kWalkMaxFramesPerRecord - 1);
  for (auto& r : prev)
    for (int32_t& v : r) v = 0;
  frames = 0;
}

void WalkFrameState::predict(int32_t out[5]) const {
  for (int k = 0; k < 5; ++k) {
    if (frames == 0) out[k] = 0;
    else if (frames == 1) out[k] = prev[0][k];
    else out[k] = static_cast<int32_t>(2 * static_cast<int64_t>(prev[0][k]) - prev[1][k]);
    if (k >= 3) out[k] &= 0xFFFF;  // angles: a turn
  }
}

void WalkFrameState::push(const int32_t steps[5]) {
  for (int k = 0; k < 5; ++k) prev[1][k] = prev[0][k], prev[0][k] = steps[k];
  ++frames;
}

void walk_pose_to_steps(const WalkPose& p, int32_t steps[5]) {
  steps[0] = p.position.x.raw() >> kWalkPoseShift;
  steps[1] = p.position.y.raw() >> kWalkPoseShift;
  steps[2] = p.position.z.raw() >> kWalkPoseShift;
  steps[3] = p.yaw;
  steps[4] = p.pitch;
}

WalkPose walk_steps_to_pose(const int32_t steps[5]) {
  WalkPose p;
  p.position = {Q16_16::from_raw(static_cast<int32_t>(static_cast<uint32_t>(steps[0]) << kWalkPoseShift)),
                Q16_16::from_raw(static_cast<int32_t>(static_cast<uint32_t>(steps[1]) << kWalkPoseShift)),
                Q16_16::from_raw(static_cast<int32_t>(static_cast<uint32_t>(steps[2]) << kWalkPoseShift))};
  p.yaw = static_cast<uint16_t>(steps[3]);
  p.pitch = static_cast<uint16_t>(steps[4]);
  return p;
}

uint32_t WalkFrameDecoder::read_count(ArithDecoder& d, uint8_t max_frames) {
  if (max_frames == 0 || max_frames > kWalkMaxFramesPerRecord) return 0;
  const uint32_t n = d.decode_unary(state_.record_frames, kWalkMaxFramesPerRecord - 1, max_frames - 1u) + 1u;
  return d.ok() ? n : 0;
}

Status WalkFrameDecoder::consume(const uint8_t* payload, uint32_t size, const uint16_t* hot, uint32_t hot_count,
                                 uint8_t* view_of, uint16_t* stamp, const bool* fresh, uint8_t views, WalkPose* pose) {
  ArithDecoder d;
  Status s = d.init(payload, size);
  if (s == Status::ok) s = decode(d, hot, hot_count, view_of, stamp, fresh, views, pose);
  return s == Status::ok ? d.finish() : s;
}

Status WalkFrameDecoder::decode(ArithDecoder& d, const uint16_t* hot, uint32_t hot_count, uint8_t* view_of, uint16_t* stamp,
                                const bool* fresh, uint8_t views, WalkPose* pose) {
  if (views == 0 || views > kWalkMaxViews) return Status::invalid_argument;
  int32_t pred[5], steps[5];
  state_.predict(pred);
  for (int k = 0; k < 5; ++k) {
    const int64_t v = static_cast<int64_t>(pred[k]) + d.decode_signed(state_.zero[k], state_.mag[k], 6, 6, 3);
    if (k >= 3) {
      steps[k] = static_cast<int32_t>(v & 0xFFFF);
    } else {
      // Positions stay inside Q16.16 (steps of 2^12 raw).
      if (v < -(int64_t{1} << 19) || v >= (int64_t{1} << 19)) return d.ok() ? Status::malformed : d.status();
      steps[k] = static_cast<int32_t>(v);
    }
  }
  if (!d.ok()) return d.status();
  const int other_bits = walk_other_view_bits(views);
  const uint16_t now = walk_frame_stamp(state_.frames);
  for (uint32_t i = 0, kept = 1; i < hot_count; ++i) {
    uint8_t& v = view_of[hot[i]];
    if (v >= views) v = 0;
    if (views > 1) {
      kept = static_cast<uint32_t>(d.decode_bit(state_.same_view[walk_view_context(stamp[hot[i]], state_.frames, fresh[v], static_cast<int>(kept))]));
      if (!kept) {
        const uint32_t k = d.decode_bits_bypass(other_bits);
        if (k >= static_cast<uint32_t>(views - 1)) return d.ok() ? Status::malformed : d.status();
        v = static_cast<uint8_t>(k >= v ? k + 1 : k);
      }
    }
    stamp[hot[i]] = now;
  }
  if (!d.ok()) return d.status();
  state_.push(steps);
  *pose = walk_steps_to_pose(steps);
  return Status::ok;
}

}  // namespace vds
