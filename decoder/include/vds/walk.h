// vds client library: the walkthrough stream's own chunks besides the
// geometry (vds/walk_geometry.h): its parameters, view updates and frame
// records, and the camera of a pose. docs/walkthrough.md, "The walkthrough
// stream", has the layout; the encoder writes them with the same
// functions (vds/enc/walk_stream.h), so both sides compute every camera
// alike.
//
// The chunks, in order: any view updates due at a frame (WVUP, then the
// view's IMGH and IMGD chunks), then a WFRM record of that frame and up to
// WLKP's frames-per-record - 1 frames after it (a record ends before a
// frame that has view updates) — per frame its geometry, pose and each hot
// triangle's view, all in one arithmetic-coded record. The client draws
// each frame as it reads it from the record: every hot triangle mapped
// from the view the record names for it.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arith.h"
#include "vds/container.h"
#include "vds/fixed.h"
#include "vds/render_camera.h"
#include "vds/status.h"

namespace vds {

namespace chunk {
constexpr uint32_t kWalkParams = fourcc('W', 'L', 'K', 'P');  // once, before any other walkthrough chunk
constexpr uint32_t kWalkView = fourcc('W', 'V', 'U', 'P');    // a view update: slot and camera; its image follows
constexpr uint32_t kWalkFrame = fourcc('W', 'F', 'R', 'M');   // a frame: its geometry, camera and each hot triangle's view
}  // namespace chunk

constexpr uint8_t kWalkMaxViews = 8;

// A camera pose: position (world units) and binary angles (2^-16 turn):
// yaw about +Z from +X, pitch up from the horizon (Quake's axes).
struct WalkPose {
  Vec3<Q16_16> position;
  uint16_t yaw = 0;
  uint16_t pitch = 0;
};

// The camera of a pose with the stream's intrinsics (HEAD focal lengths,
// principal point and clip planes): camera x right, y down, z forward.
// invalid_argument when the result fails validate_camera().
Status walk_camera(const StreamHeader& h, const WalkPose& pose, Camera* out);

// WLKP payload (16 bytes): u16 polygon slots, u8 view slots, u8 the most
// frames a WFRM record holds (1..kWalkMaxFramesPerRecord), i32 vertex grid
// quantum (raw Q16.16, a power of two), i32 the views' focal length
// (Q16.16 pixels; views may see wider than the screen), u16 the views'
// width and u16 height (16 up to the frame's; the principal point is their
// centre).
constexpr uint8_t kWalkMaxFramesPerRecord = 8;
struct WalkParams {
  uint16_t slots = 0;
  uint8_t views = 0;
  uint8_t frames_per_record = 1;
  int32_t quantum_raw = 0;
  int32_t view_focal_q16 = 0;
  uint16_t view_width = 0, view_height = 0;
  // The schedule the stream was shaped for (0, 0, 0: none; the client
  // shows each frame when its data is whole): a link carrying rate_bytes
  // stream bytes a second into a client holding up to buffer_bytes it has
  // not yet taken shows frame i at preroll_ms + i frame periods after the
  // stream's first byte, every frame's data there in time.
  uint32_t rate_bytes = 0;
  uint32_t buffer_bytes = 0;
  uint32_t preroll_ms = 0;
};
constexpr uint32_t kWalkParamsBytes = 28;
constexpr uint32_t kWalkMaxPrerollMs = 600000;  // ten minutes
// The camera of a view: walk_camera with the views' focal length times
// zoom / 16 (kWalkZoomUnit: the WLKP focal length) and their centre as the
// principal point.
constexpr uint8_t kWalkZoomUnit = 16, kWalkMaxZoom = 64;
Status walk_view_camera(const StreamHeader& h, const WalkParams& w, const WalkPose& pose, Camera* out,
                        uint8_t zoom = kWalkZoomUnit);
Status walk_params_from_bytes(const uint8_t* p, uint32_t size, WalkParams* out);
void walk_params_to_bytes(const WalkParams& w, uint8_t out[kWalkParamsBytes]);

// WVUP payload (17 or 18 bytes): u8 view slot (bits 0..6) and "predict"
// (bit 7: the client draws its prediction of the view into the slot before
// the image, which may then be a residual against it), then the pose: i32
// x, y, z (raw Q16.16), u16 yaw, u16 pitch; then, in an 18-byte payload,
// u8 zoom (17..64: the view's focal length is WLKP's times zoom / 16, a
// narrower view with finer texels; 17 bytes: 16, WLKP's own).
constexpr uint32_t kWalkViewBytes = 17;
constexpr uint32_t kWalkViewMaxBytes = 18;
constexpr uint8_t kWalkViewPredict = 0x80;
struct WalkViewUpdate {
  uint8_t slot = 0;
  bool predict = false;
  WalkPose pose;
  uint8_t zoom = kWalkZoomUnit;
};
Status walk_view_from_bytes(const uint8_t* p, uint32_t size, WalkViewUpdate* out);
// The payload's size (17 when the zoom is 16, else 18).
uint32_t walk_view_to_bytes(const WalkViewUpdate& u, uint8_t out[kWalkViewMaxBytes]);

// Bypass bins naming a view other than a triangle's last in a frame
// record: ceil(log2(views - 1)).
constexpr int walk_other_view_bits(uint8_t views) {
  int b = 0;
  while ((1 << b) < views - 1) ++b;
  return b;
}

// Positions in a frame record are on a grid of 1/16 world unit.
constexpr int kWalkPoseShift = 12;  // raw Q16.16 per step: 2^12

// The contexts and history of the frame records, shared with the encoder.
struct WalkFrameState {
  ArithContext zero[5];
  ArithContext mag[5][6];
  // "Same view as last time", by the triangle's class — hot in the frame
  // before and its view not updated since (0), hot before and its view
  // updated (1), newly hot (2) — times 2, plus 1 if the triangle before
  // it in the frame kept its view (walk_view_context).
  ArithContext same_view[6];
  ArithContext record_frames[kWalkMaxFramesPerRecord - 1];  // a record's frame count - 1, truncated unary
  int32_t prev[2][5] = {};  // the last two poses as steps: x, y, z, yaw, pitch
  uint32_t frames = 0;
  void reset();
  // The prediction of the next pose's steps (constant velocity after two frames).
  void predict(int32_t out[5]) const;
  void push(const int32_t steps[5]);
};

// The context of a hot triangle's "same view" bin (WalkFrameState::
// same_view): `stamp` is the slot's frame stamp (the frame, plus one,
// modulo 2^16, it was last hot in; 0 never), `frame` the index of the
// frame being read, `fresh` whether its view slot took a view update
// since the frame before, `kept` whether the triangle before it in the
// frame kept its view (1 for the first).
inline int walk_view_context(uint16_t stamp, uint32_t frame, bool fresh, int kept) {
  const bool was_hot = frame > 0 && stamp == static_cast<uint16_t>(frame);
  return 2 * (was_hot ? (fresh ? 1 : 0) : 2) + kept;
}
inline uint16_t walk_frame_stamp(uint32_t frame) { return static_cast<uint16_t>(frame + 1u); }

// WFRM payload, one arithmetic-coded stream: the number of frames it
// holds less one (truncated unary, at most WLKP's frames-per-record - 1;
// read_count), then per frame: its geometry (WalkGeometry::decode,
// vds/walk_geometry.h), its pose as five signed ueg3 residuals against
// WalkFrameState::predict (angles wrap at a turn), then per hot triangle
// (ascending slot) a "same view as last time" bin in the context
// walk_view_context gives and, when not, the view among the others in
// ceil(log2(views - 1)) bypass bins.
class WalkFrameDecoder {
 public:
  void reset() { state_.reset(); }
  // A record's frame count (1..max_frames); 0 when the data is bad.
  uint32_t read_count(ArithDecoder& d, uint8_t max_frames);
  // Reads a record's pose and views: the pose, and `view_of[hot[i]]` for
  // each hot slot (its last view in, its new view out; views < `views`),
  // `stamp[hot[i]]` set to this frame's stamp (walk_frame_stamp); `fresh`
  // per view slot: a view update since the frame before. malformed for a
  // view out of range; truncated.
  Status decode(ArithDecoder& d, const uint16_t* hot, uint32_t hot_count, uint8_t* view_of, uint16_t* stamp,
                const bool* fresh, uint8_t views, WalkPose* pose);
  // The same from a payload of its own (then the coder's end check).
  Status consume(const uint8_t* payload, uint32_t size, const uint16_t* hot, uint32_t hot_count, uint8_t* view_of,
                 uint16_t* stamp, const bool* fresh, uint8_t views, WalkPose* pose);

 private:
  WalkFrameState state_{};
};

// Pose <-> the record's steps.
void walk_pose_to_steps(const WalkPose& p, int32_t steps[5]);
WalkPose walk_steps_to_pose(const int32_t steps[5]);

}  // namespace vds
