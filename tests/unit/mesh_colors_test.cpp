// Mesh colors and their codec: the topology's edge numbering, the lattice
// layout (every sample of a level named exactly once, shared edges named
// alike from both faces), the transform pair, the paper-mode codec through
// the client library (bounds on error, bytes falling with quality, the
// encoder's edge reconstruction equal to the client's), refused headers,
// every prefix and flipped bytes refused cleanly, the textured import of the
// duck and mrfixit, and the IQM check.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <string>

#include "vds/enc/mesh_colors.h"
#include "vds/enc/model_render.h"
#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"
#include "vds/mesh_colors.h"
#include "vds/ref/scene.h"

namespace {

using namespace vds;

// A tetrahedron: every edge shared by two faces in opposite directions.
const uint16_t kTetra[] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};

// The codec's fidelity to a level's own samples: chroma on the level's lattice.
vds::enc::MccOptions paper_mode() {
  vds::enc::MccOptions o;
  o.paper = true;
  o.chroma_half = false;
  return o;
}
vds::enc::MccOptions full_chroma() {
  vds::enc::MccOptions o;
  o.chroma_half = false;
  return o;
}

struct Held {
  std::vector<uint8_t> work;
  Arena arena;
  mc::MeshColors mc;
  Status init(const std::vector<uint16_t>& tri, uint32_t vertices) {
    const uint32_t faces = static_cast<uint32_t>(tri.size() / 3);
    work.assign(mc::MeshColors::init_bytes(faces, vertices), 0);
    arena = Arena(work.data(), work.size());
    return mc.init(arena, tri.data(), faces, vertices);
  }
};

TEST(MeshColorsTopology, EdgesAreNumberedByFirstAppearanceAndSharedBothWays) {
  std::vector<uint8_t> work(mc::topology_bytes(4));
  Arena arena(work.data(), work.size());
  mc::Topology t;
  ASSERT_EQ(mc::build_topology(arena, kTetra, 4, 4, &t), Status::ok);
  EXPECT_EQ(t.edges, 6u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(t.face_edge[k], static_cast<uint32_t>(k) << 1);  // face 0 names them first
  std::map<uint32_t, int> uses, reversed;
  for (uint32_t f = 0; f < 4; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t fe = t.face_edge[3 * f + k], e = fe >> 1;
      ++uses[e];
      reversed[e] += fe & 1;
      const uint16_t a = kTetra[3 * f + k], b = kTetra[3 * f + (k + 1) % 3];
      EXPECT_EQ(t.edge_vertex[2 * e], (fe & 1) ? b : a);
      EXPECT_EQ(t.edge_vertex[2 * e + 1], (fe & 1) ? a : b);
    }
  for (uint32_t e = 0; e < 6; ++e) {
    EXPECT_EQ(uses[e], 2);
    EXPECT_EQ(reversed[e], 1);  // the second face runs it the other way
  }
  // Scratch given back: only the persistent arrays stay carved.
  EXPECT_LE(arena.used(), 3 * 4 * 4 + 6 * 4 * 2 + 16u);
}

TEST(MeshColorsTopology, RefusesIndicesOutOfRangeAndRepeatedVertices) {
  std::vector<uint8_t> work(mc::topology_bytes(1));
  mc::Topology t;
  const uint16_t out_of_range[] = {0, 1, 3};
  const uint16_t repeated[] = {0, 1, 1};
  Arena a1(work.data(), work.size());
  EXPECT_EQ(mc::build_topology(a1, out_of_range, 1, 3, &t), Status::invalid_argument);
  Arena a2(work.data(), work.size());
  EXPECT_EQ(mc::build_topology(a2, repeated, 1, 3, &t), Status::invalid_argument);
  Arena a3(work.data(), work.size());
  EXPECT_EQ(mc::build_topology(a3, repeated, 1, mc::kMaxVertices + 1, &t), Status::invalid_argument);
  Arena small(work.data(), 8);
  EXPECT_EQ(mc::build_topology(small, kTetra, 1, 4, &t), Status::workspace_too_small);
}

// A grid of n x n quads over [0, 1]^2 (z = 0), two triangles each, the UV
// map the plane itself.
enc::TexturedModel grid_model(int n, const enc::Image& texture) {
  enc::TexturedModel m;
  m.name = "grid";
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.positions.push_back({double(x) / n, double(y) / n, 0});
  m.materials.push_back({0, {1, 1, 1}});
  m.textures.push_back(texture);
  auto uv = [&](uint32_t v) { return std::array<double, 2>{m.positions[v][0], m.positions[v][1]}; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      for (const std::array<uint32_t, 3>& t : {std::array<uint32_t, 3>{a, b, d}, std::array<uint32_t, 3>{a, d, c}}) {
        m.triangles.push_back(t);
        m.uv.push_back({uv(t[0]), uv(t[1]), uv(t[2])});
        m.colour.push_back({std::array<double, 3>{1, 1, 1}, std::array<double, 3>{1, 1, 1}, std::array<double, 3>{1, 1, 1}});
        m.material.push_back(0);
      }
    }
  return m;
}

enc::MeshColorsModel test_colors(int max_res = 5) {
  const enc::Image tex = ref::make_noise_texture(128, 11, 0x203040, 0xE0C060);
  enc::MeshColorsOptions o;
  o.max_res_log2 = max_res;
  return enc::to_mesh_colors(grid_model(4, tex), o);
}

TEST(MeshColorsLayout, EveryLatticePointNamesOneSampleAndSharedEdgesAgree) {
  enc::MeshColorsModel m = test_colors();
  // Mixed resolutions: every third face one step coarser.
  for (size_t f = 0; f < m.face_res.size(); f += 3) m.face_res[f] = static_cast<uint8_t>(m.face_res[f] - 1);
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  ASSERT_EQ(h.mc.set(m.face_res.data(), m.vertex_ycc.data(), 256), Status::ok);
  for (int level = 0; level <= h.mc.max_res_log2(); ++level) {
    const uint32_t total = h.mc.layout_level(level);
    // The position each sample stands for, from every face that names it.
    std::vector<std::array<double, 3>> where(total);
    std::vector<int> named(total, 0);
    for (uint32_t f = 0; f < h.mc.topology().faces; ++f) {
      const uint32_t R = mc::resolution(mc::level_res(m.face_res[f], level));
      for (uint32_t j = 0; j <= R; ++j)
        for (uint32_t i = 0; i + j <= R; ++i) {
          const uint32_t s = h.mc.sample_index(f, level, i, j);
          ASSERT_LT(s, total);
          std::array<double, 3> p{};
          const double w[3] = {double(R - i - j) / R, double(i) / R, double(j) / R};
          for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) p[c] += w[k] * m.positions[m.triangles[3 * f + k]][c];
          if (named[s]++ == 0) {
            where[s] = p;
          } else {
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(where[s][c], p[c], 1e-12) << "sample " << s << " level " << level;
          }
        }
    }
    // Edge samples a coarser face skips are named by the finer face only;
    // every sample is named at least once.
    for (uint32_t s = 0; s < total; ++s) EXPECT_GT(named[s], 0) << "sample " << s << " of level " << level;
  }
}

TEST(MeshColorsCodec, InverseTransformUndoesTheForward) {
  std::mt19937 rng(5);
  for (int n = 1; n <= 8; ++n)
    for (int trial = 0; trial < 200; ++trial) {
      double x[8], X[8];
      for (int i = 0; i < n; ++i) x[i] = rng() % 256;
      double mean = 0;
      for (int i = 0; i < n; ++i) mean += x[i];
      X[0] = mean / n;
      for (int k = 1; k < n; ++k) {
        X[k] = 0;
        for (int i = 0; i < n; ++i) X[k] += x[i] * std::cos(3.14159265358979323846 / n * (i + 0.5) * k);
      }
      int32_t in[8], out[8];
      for (int k = 0; k < n; ++k) in[k] = static_cast<int32_t>(std::lround(X[k] * 16));
      mc::inverse_dct(in, n, out);
      for (int i = 0; i < n; ++i) ASSERT_NEAR(out[i], x[i] * 16, 2.0) << "n " << n;
    }
}

double plane_psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double se = 0;
  for (size_t i = 0; i < a.size(); ++i) se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return se == 0 ? 99 : 10 * std::log10(255.0 * 255.0 * a.size() / se);
}

TEST(MeshColorsCodec, RoundTripThroughTheClientWithinBoundsAndSmallerAtLowerQuality) {
  const enc::MeshColorsModel m = test_colors();
  ASSERT_EQ(m.max_res, 5);
  size_t previous = SIZE_MAX;
  const double quality[] = {0.1, 1, 4};
  // The thesis's steps quantise the DC (the mean) with the tables' first
  // step: coarse for chroma at high quality factors.
  const double min_luma[] = {41, 30, 23}, min_chroma[] = {44, 30, 18};
  for (int qi = 0; qi < 3; ++qi) {
    const enc::MccEncoded e = enc::encode_mesh_colors(m, quality[qi], paper_mode());
    ASSERT_EQ(e.levels.size(), 5u);
    size_t bytes = 0;
    for (int level = 0; level < m.max_res; ++level) {
      bytes += e.level_bytes(level);
      const auto planes = enc::decode_mesh_colors_level(m, e, level);
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(planes[c].size(), m.levels[level][c].size());
        // Vertex samples travel uncoded.
        for (size_t v = 0; v < m.positions.size(); ++v) ASSERT_EQ(planes[c][v], m.levels[level][c][v]);
        EXPECT_GE(plane_psnr(planes[c], m.levels[level][c]), c == 0 ? min_luma[qi] : min_chroma[qi])
            << "quality " << quality[qi] << " level " << level << " component " << c;
      }
    }
    EXPECT_LT(bytes, previous) << "quality " << quality[qi];
    previous = bytes;
  }
}

TEST(MeshColorsCodec, TheVdsModeRoundTripsWithinBoundsAndBeatsThePaperMode) {
  const enc::MeshColorsModel m = test_colors();
  auto level0 = [&](double quality, const enc::MccOptions& o, double* psnr) {
    const enc::MccEncoded e = enc::encode_mesh_colors(m, quality, o);
    const auto planes = enc::decode_mesh_colors_level(m, e, 0);
    *psnr = plane_psnr(planes[0], m.levels[0][0]);
    return e.level_bytes(0);
  };
  // Bounds, and fewer bytes at lower quality.
  const double quality[] = {0.125, 0.25, 0.5, 1, 2, 4, 8};
  const double min_psnr[] = {48, 45, 42, 39, 35, 31, 27};
  std::vector<std::pair<size_t, double>> vds;
  for (int qi = 0; qi < 7; ++qi) {
    double p;
    const size_t bytes = level0(quality[qi], full_chroma(), &p);
    EXPECT_GE(p, min_psnr[qi]) << "quality " << quality[qi];
    if (!vds.empty()) EXPECT_LT(bytes, vds.back().first) << "quality " << quality[qi];
    vds.emplace_back(bytes, p);
    // Vertex samples: losslessly with a step of 1, else within the step
    // (to the nearest step but at the ends of 0..255), the same at every
    // level; every level decodes.
    enc::MccOptions lossless;
    lossless.vertex_step = 1;
    const enc::MccEncoded exact = enc::encode_mesh_colors(m, quality[qi], lossless);
    EXPECT_EQ(exact.header[3] & mc::kFlagVertexStep, 0);
    const int step = enc::vertex_step_for_quality(quality[qi]);
    const enc::MccEncoded e = enc::encode_mesh_colors(m, quality[qi]);
    EXPECT_EQ((e.header[3] & mc::kFlagVertexStep) != 0, step > 1);
    if (step > 1) {
      EXPECT_EQ(e.header[mc::kHeaderFixedBytes], step);
      EXPECT_LT(e.header.size(), exact.header.size()) << "quality " << quality[qi];
    }
    const auto lossy0 = enc::decode_mesh_colors_level(m, e, 0);
    // The samples the encoder coded the levels from are the client's.
    const enc::MeshColorsModel stepped = enc::with_stepped_vertex_samples(m, step);
    for (int c = 0; c < 3; ++c)
      for (size_t v = 0; v < m.positions.size(); ++v) ASSERT_EQ(lossy0[c][v], stepped.vertex_ycc[3 * v + c]);
    for (int level = 0; level < m.max_res; ++level) {
      const auto planes = enc::decode_mesh_colors_level(m, exact, level);
      const auto lossy = enc::decode_mesh_colors_level(m, e, level);
      for (int c = 0; c < 3; ++c)
        for (size_t v = 0; v < m.positions.size(); ++v) {
          ASSERT_EQ(planes[c][v], m.levels[level][c][v]);
          ASSERT_LE(std::abs(lossy[c][v] - m.levels[level][c][v]), step);
          ASSERT_EQ(lossy[c][v], lossy0[c][v]);
        }
    }
  }
  // Every paper-mode point is beaten: some vds point has no more bytes and a higher PSNR.
  for (double q : {0.25, 1.0, 4.0}) {
    double p;
    const size_t bytes = level0(q, paper_mode(), &p);
    bool beaten = false;
    for (const auto& [b, pv] : vds) beaten |= b <= bytes && pv >= p;
    EXPECT_TRUE(beaten) << "paper quality " << q << ": " << bytes << " bytes, " << p << " dB";
  }
}

TEST(MeshColorsCodec, AFlatColourCostsAlmostNothingInTheVdsMode) {
  enc::MeshColorsModel m = test_colors();
  for (auto& level : m.levels)
    for (int c = 0; c < 3; ++c) std::fill(level[c].begin(), level[c].end(), static_cast<uint8_t>(90 + 40 * c));
  for (size_t i = 0; i < m.vertex_ycc.size(); ++i) m.vertex_ycc[i] = static_cast<uint8_t>(90 + 40 * (i % 3));
  for (bool half : {false, true}) {
    enc::MccOptions o;
    o.chroma_half = half;
    const enc::MccEncoded e = enc::encode_mesh_colors(m, 2, o);
    for (int level = 0; level < m.max_res; ++level) {
      EXPECT_LT(e.level_bytes(level), 40u) << "level " << level;
      const auto planes = enc::decode_mesh_colors_level(m, e, level);
      // Flat everywhere, within half the mean's step (4 levels at quality 2)
      // of the colour; chroma from the next level's lattice is filled in
      // between it and the (exact) vertex samples.
      for (int c = 0; c < 3; ++c)
        for (size_t i = m.positions.size(); i < planes[c].size(); ++i) {
          if (c == 0 || !half) ASSERT_EQ(planes[c][i], planes[c][m.positions.size()]) << "level " << level << " sample " << i;
          ASSERT_LE(std::abs(planes[c][i] - m.levels[level][c][i]), 2) << "level " << level << " sample " << i;
        }
    }
  }
}

TEST(MeshColorsCodec, TheVdsEncodersSampleDensityFallsWithQualityAndSoDoTheSamples) {
  EXPECT_EQ(enc::density_for_quality(0.125), 1.0);
  EXPECT_EQ(enc::density_for_quality(0.25), 1.0);
  EXPECT_DOUBLE_EQ(enc::density_for_quality(1), 0.5);
  EXPECT_EQ(enc::density_for_quality(100), 0.25);
  const enc::Image tex = ref::make_noise_texture(128, 11, 0x203040, 0xE0C060);
  uint32_t previous = UINT32_MAX;
  for (double q : {0.25, 1.0, 4.0}) {
    enc::MeshColorsOptions o;
    o.density = enc::density_for_quality(q);
    const uint32_t samples = enc::to_mesh_colors(grid_model(4, tex), o).samples(0);
    EXPECT_LT(samples, previous) << "quality " << q;
    previous = samples;
  }
}

// The choice of face resolutions: a face takes the coarsest lattice that
// predicts its samples as well as coding them does. A flat texture needs
// only the vertex samples; noise coded finely keeps its resolutions; coded
// coarsely, more faces are made coarser; the conversion keeps the vertex
// samples of the resolutions it started from.
TEST(MeshColorsLayout, FacesTakeACoarserLatticeWhereItPredictsThemAsWellAsCodingDoes) {
  enc::MeshColorsOptions o;
  o.max_res_log2 = 5;
  const enc::Image noise = ref::make_noise_texture(128, 11, 0x203040, 0xE0C060);
  const enc::Image flat = ref::make_noise_texture(128, 11, 0x6080A0, 0x6080A0);
  const enc::MeshColorsModel full = enc::to_mesh_colors(grid_model(4, noise), o);
  const enc::MeshColorsModel plain = enc::to_mesh_colors(grid_model(4, flat), o);
  ASSERT_EQ(full.max_res, 5);
  const auto flat_sse = enc::coarser_face_sse(plain);
  for (size_t f = 0; f < flat_sse.size(); ++f) {
    ASSERT_EQ(flat_sse[f].size(), plain.face_res[f] + 1u);
    for (double e : flat_sse[f]) EXPECT_LT(e, 1e-9) << "face " << f;
  }
  const auto noise_sse = enc::coarser_face_sse(full);
  for (size_t f = 0; f < noise_sse.size(); ++f) {
    EXPECT_EQ(noise_sse[f][0], 0.0);
    EXPECT_GT(noise_sse[f].back(), noise_sse[f][1]) << "face " << f;  // coarser predicts worse
  }
  const enc::MccOptions codec;
  for (uint8_t r : enc::rd_face_resolutions(plain, 1, codec)) EXPECT_EQ(r, 0);
  auto coarser = [&](double quality) {
    const std::vector<uint8_t> r = enc::rd_face_resolutions(full, quality, codec);
    size_t n = 0;
    for (size_t f = 0; f < r.size(); ++f) {
      EXPECT_LE(r[f], full.face_res[f]);
      n += r[f] < full.face_res[f];
    }
    return n;
  };
  const size_t fine = coarser(0.125), rough = coarser(32);
  EXPECT_EQ(fine, 0u);
  EXPECT_GT(rough, fine);
  // Through the conversion: the chosen resolutions, the vertex samples kept.
  const enc::MeshColorsModel chosen = enc::to_mesh_colors_rd(grid_model(4, noise), o, 32, codec);
  EXPECT_EQ(chosen.face_res, enc::rd_face_resolutions(full, 32, codec));
  EXPECT_LT(chosen.samples(0), full.samples(0));
  EXPECT_EQ(chosen.vertex_ycc, full.vertex_ycc);
}

// The encoder's measured choices: a flat texture is drawn as well from the
// vertex samples alone, so its faces are made coarser; a texture whose
// detail is all in the chroma (red and green of equal luma) keeps its
// chroma on each level's own lattice at a fine quality.
TEST(MeshColorsChoice, TheEncoderKeepsWhatItsViewsShowBest) {
  enc::MeshColorsOptions mo;
  mo.max_res_log2 = 5;
  auto choose = [&](const enc::Image& tex, double quality) {
    const enc::TexturedModel model = grid_model(4, tex);
    const enc::ModelViews views = enc::orbit_views(model.positions, 4, 96, 96, 2, 2);
    return enc::choose_colours(model, mo, quality, enc::MccOptions{}, views, enc::render_references(model, views));
  };
  const enc::ColourChoice flat = choose(ref::make_noise_texture(128, 11, 0x6080A0, 0x6080A0), 1);
  EXPECT_TRUE(flat.coarser_faces);
  const enc::MeshColorsModel fine = enc::to_mesh_colors(grid_model(4, ref::make_noise_texture(128, 11, 0x6080A0, 0x6080A0)), mo);
  const enc::MccEncoded fine_coded = enc::encode_mesh_colors(fine, 1);
  EXPECT_LT(flat.bytes, fine_coded.header.size() + fine_coded.level_bytes(0));
  EXPECT_GT(flat.psnr, 40.0);
  const enc::ColourChoice chroma = choose(ref::make_noise_texture(128, 11, 0xFF0000, 0x008200), 0.25);
  EXPECT_FALSE(chroma.chroma_half);
  EXPECT_EQ(chroma.coded.header[3] & mc::kFlagChromaHalf, 0);
  EXPECT_EQ(chroma.bytes, chroma.coded.header.size() + chroma.coded.level_bytes(0));
}

TEST(MeshColorsLayout, FacesOnASeamWhoseSidesDifferGetTwiceTheResolution) {
  // Two halves of a black-and-white texture: the grid's right half maps to
  // the white half, so the seam down the middle has a different colour on
  // each side.
  enc::Image tex(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) tex.at(x, y, c) = x < 32 ? 0 : 255;
  enc::TexturedModel m = grid_model(4, tex);
  for (size_t f = 0; f < m.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) m.uv[f][k][0] *= 0.45;  // all of it in the black half
  enc::MeshColorsOptions off;
  off.seam_boost = false;
  // A map without seams: nothing changes.
  EXPECT_EQ(enc::to_mesh_colors(m).face_res, enc::to_mesh_colors(m, off).face_res);
  enc::TexturedModel seam = m;
  for (size_t f = 0; f < seam.triangles.size(); ++f) {
    double cx = 0;
    for (int k = 0; k < 3; ++k) cx += seam.positions[seam.triangles[f][k]][0] / 3;
    if (cx > 0.5)
      for (int k = 0; k < 3; ++k) seam.uv[f][k][0] += 0.5;  // the right half's faces: white
  }
  const enc::MeshColorsModel a = enc::to_mesh_colors(seam, off), b = enc::to_mesh_colors(seam);
  int boosted = 0;
  for (size_t f = 0; f < a.face_res.size(); ++f) {
    EXPECT_GE(b.face_res[f], a.face_res[f]);
    boosted += b.face_res[f] > a.face_res[f];
  }
  // The faces along the middle column of edges: 2 of each of the 4 rows, on each side.
  EXPECT_GE(boosted, 8);
  EXPECT_LE(boosted, 16);
}

TEST(MeshColorsCodec, HeadersAClientCannotTakeAreRefused) {
  const enc::MeshColorsModel m = test_colors(3);
  const enc::MccEncoded e = enc::encode_mesh_colors(m, 1, paper_mode());
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  ASSERT_EQ(h.mc.read_header(e.header.data(), e.header.size()), Status::ok);
  EXPECT_EQ(h.mc.max_res_log2(), 3);
  auto with = [&](size_t at, uint8_t value) {
    std::vector<uint8_t> b = e.header;
    b[at] = value;
    return h.mc.read_header(b.data(), b.size());
  };
  EXPECT_EQ(with(0, 0), Status::malformed);
  EXPECT_EQ(with(0, 2), Status::unsupported_version);
  EXPECT_TRUE(is_error(with(1, 1)));  // a paper header read as a vds one: its raw vertex bytes are no code
  EXPECT_EQ(with(1, 7), Status::malformed);
  EXPECT_EQ(with(2, 11), Status::malformed);  // above kMaxResLog2
  EXPECT_TRUE(is_error(with(2, 4)));         // not the largest face's (the codes end early)
  EXPECT_EQ(with(3, 1), Status::malformed);  // flags
  EXPECT_EQ(with(3, mc::kFlagVertexStep), Status::malformed);  // a step for the paper mode's raw samples
  EXPECT_EQ(with(3, 8), Status::malformed);  // no such flag
  // A vds header with a vertex step: the step must be 2..kMaxVertexStep.
  {
    enc::MccOptions stepped;
    stepped.vertex_step = 4;
    const enc::MccEncoded v = enc::encode_mesh_colors(m, 1, stepped);
    ASSERT_EQ(v.header[3] & mc::kFlagVertexStep, mc::kFlagVertexStep);
    ASSERT_EQ(v.header[mc::kHeaderFixedBytes], 4);
    ASSERT_EQ(h.mc.read_header(v.header.data(), v.header.size()), Status::ok);
    for (uint8_t bad : {uint8_t{0}, uint8_t{1}, static_cast<uint8_t>(mc::kMaxVertexStep + 1), uint8_t{255}}) {
      std::vector<uint8_t> b = v.header;
      b[mc::kHeaderFixedBytes] = bad;
      EXPECT_EQ(h.mc.read_header(b.data(), b.size()), Status::malformed) << int{bad};
    }
    std::vector<uint8_t> cut(v.header.begin(), v.header.begin() + mc::kHeaderFixedBytes);
    EXPECT_EQ(h.mc.read_header(cut.data(), cut.size()), Status::truncated);
    // Every sample a whole number of steps from its prediction: another step reads other samples.
    std::vector<uint8_t> b = v.header;
    b[mc::kHeaderFixedBytes] = 5;
    const Status other = h.mc.read_header(b.data(), b.size());
    if (other == Status::ok) {
      Held again;
      ASSERT_EQ(again.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
      ASSERT_EQ(again.mc.read_header(v.header.data(), v.header.size()), Status::ok);
      EXPECT_FALSE(std::equal(h.mc.vertex_samples(), h.mc.vertex_samples() + 3 * m.positions.size(), again.mc.vertex_samples()));
    }
  }
  std::vector<uint8_t> zero_quality = e.header;
  zero_quality[4] = zero_quality[5] = 0;
  EXPECT_EQ(h.mc.read_header(zero_quality.data(), zero_quality.size()), Status::malformed);
  EXPECT_EQ(with(6, static_cast<uint8_t>(e.header[6] + 1)), Status::malformed);  // vertex count
  EXPECT_EQ(with(8, static_cast<uint8_t>(e.header[8] + 1)), Status::malformed);  // face count
  std::vector<uint8_t> longer = e.header;
  longer.push_back(0);
  EXPECT_EQ(h.mc.read_header(longer.data(), longer.size()), Status::malformed);
  // A level beyond the header's, and a level before any header.
  ASSERT_EQ(h.mc.read_header(e.header.data(), e.header.size()), Status::ok);
  std::vector<uint8_t> level = e.levels[0][0];
  level[0] = 3;
  const uint32_t total = h.mc.layout_level(0);
  std::vector<uint8_t> y(total), cb(total), cr(total);
  EXPECT_EQ(h.mc.decode_level(level.data(), level.size(), mc::Planes{y.data(), cb.data(), cr.data()}), Status::malformed);
  Held fresh;
  ASSERT_EQ(fresh.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  EXPECT_EQ(fresh.mc.decode_level(e.levels[0][0].data(), e.levels[0][0].size(), mc::Planes{y.data(), cb.data(), cr.data()}),
            Status::invalid_argument);
}

class MeshColorsModes : public ::testing::TestWithParam<bool> {};

TEST_P(MeshColorsModes, EveryPrefixAndFlippedBytesAreRefusedCleanly) {
  const enc::MeshColorsModel m = test_colors(4);
  enc::MccOptions o;
  o.paper = GetParam();
  const enc::MccEncoded e = enc::encode_mesh_colors(m, 1, o);
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  for (size_t n = 0; n < e.header.size(); ++n)
    EXPECT_TRUE(is_error(h.mc.read_header(e.header.data(), n))) << "header prefix " << n;
  ASSERT_EQ(h.mc.read_header(e.header.data(), e.header.size()), Status::ok);
  const uint32_t total = h.mc.layout_level(0);
  std::vector<uint8_t> y(total), cb(total), cr(total);
  const mc::Planes planes{y.data(), cb.data(), cr.data()};
  for (int level = 0; level < 4; ++level) {
    ASSERT_EQ(e.levels[level].size(), 1u);
    const std::vector<uint8_t>& b = e.levels[level][0];
    ASSERT_EQ(h.mc.decode_level(b.data(), b.size(), planes), Status::ok);
    for (size_t n = 0; n < b.size(); ++n) EXPECT_TRUE(is_error(h.mc.decode_level(b.data(), n, planes))) << n;
  }
  // Flipped bytes: any status, never a crash or a write outside the planes
  // (the sanitizers watch), and the level's size stays its own.
  std::mt19937 rng(3);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> b = e.levels[trial % 4][0];
    const size_t at = 1 + rng() % (b.size() - 1);
    b[at] ^= static_cast<uint8_t>(1 + rng() % 255);
    refused += is_error(h.mc.decode_level(b.data(), b.size(), planes));
  }
  EXPECT_GT(refused, 150);  // most damage is caught by the exact-length rule or a value no encoder writes
}

// A level cut into chunks that fit a client's chunk buffer decodes to the
// same samples; its chunks must come in order, each after the last.
TEST_P(MeshColorsModes, LevelsInChunksDecodeAlikeAndOnlyInOrder) {
  const enc::MeshColorsModel m = test_colors();
  enc::MccOptions o;
  o.paper = GetParam();
  const enc::MccEncoded whole = enc::encode_mesh_colors(m, 1, o);
  o.max_chunk = 200;
  const enc::MccEncoded cut = enc::encode_mesh_colors(m, 1, o);
  ASSERT_GT(cut.levels[0].size(), 3u);
  for (int level = 0; level < m.max_res; ++level) {
    for (const auto& c : cut.levels[level]) EXPECT_LE(c.size(), 200u);
    EXPECT_EQ(enc::decode_mesh_colors_level(m, cut, level), enc::decode_mesh_colors_level(m, whole, level)) << level;
  }
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  ASSERT_EQ(h.mc.read_header(cut.header.data(), cut.header.size()), Status::ok);
  const uint32_t total = h.mc.layout_level(0);
  std::vector<uint8_t> y(total), cb(total), cr(total);
  const mc::Planes planes{y.data(), cb.data(), cr.data()};
  const auto& c0 = cut.levels[0];
  const auto& c1 = cut.levels[1];
  EXPECT_EQ(h.mc.decode_level(c0[1].data(), c0[1].size(), planes), Status::malformed);  // no first chunk yet
  ASSERT_EQ(h.mc.decode_level(c0[0].data(), c0[0].size(), planes), Status::ok);
  EXPECT_FALSE(h.mc.level_complete());
  EXPECT_EQ(h.mc.decode_level(c0[2].data(), c0[2].size(), planes), Status::malformed);  // one skipped
  ASSERT_EQ(h.mc.decode_level(c0[0].data(), c0[0].size(), planes), Status::ok);
  EXPECT_EQ(h.mc.decode_level(c1[1].data(), c1[1].size(), planes), Status::malformed);  // another level's
  for (const auto& c : c1) ASSERT_EQ(h.mc.decode_level(c.data(), c.size(), planes), Status::ok);
  EXPECT_TRUE(h.mc.level_complete());
  EXPECT_EQ(h.mc.decoding_level(), 1);
}

// kFlagVertexColours: the vertex samples are not in MCLH but the colours
// that came with the vertices; a header that says so is refused without them.
TEST_P(MeshColorsModes, VertexSamplesFromTheVertexColours) {
  const enc::MeshColorsModel m = test_colors();
  enc::MccOptions o;
  o.paper = GetParam();
  const enc::MccEncoded inside = enc::encode_mesh_colors(m, 1, o);
  o.vertex_colours_outside = true;
  const enc::MccEncoded outside = enc::encode_mesh_colors(m, 1, o);
  EXPECT_EQ(outside.header[3] & mc::kFlagVertexColours, mc::kFlagVertexColours);
  EXPECT_LT(outside.header.size(), inside.header.size());
  const size_t V = m.positions.size();
  std::array<std::vector<uint8_t>, 3> vc;
  for (int c = 0; c < 3; ++c)
    for (size_t v = 0; v < V; ++v) vc[c].push_back(m.vertex_ycc[3 * v + c]);
  const mc::Planes planes{vc[0].data(), vc[1].data(), vc[2].data()};
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(V)), Status::ok);
  EXPECT_EQ(h.mc.read_header(outside.header.data(), outside.header.size()), Status::malformed);
  ASSERT_EQ(h.mc.read_header(outside.header.data(), outside.header.size(), &planes), Status::ok);
  for (size_t i = 0; i < 3 * V; ++i) ASSERT_EQ(h.mc.vertex_samples()[i], m.vertex_ycc[i]);
  // The same samples at every level as with the vertex samples inside.
  for (int level = 0; level < m.max_res; ++level)
    EXPECT_EQ(enc::decode_mesh_colors_level(m, outside, level), enc::decode_mesh_colors_level(m, inside, level)) << level;
  for (size_t n = 0; n < outside.header.size(); ++n)
    EXPECT_TRUE(is_error(h.mc.read_header(outside.header.data(), n, &planes))) << "prefix " << n;
}

// kFlagChromaHalf: a level's chroma is coded from the next level's samples;
// the client holds them at their lattice points (2 i, 2 j) and fills every
// other point with the rounded-up mean of its two neighbours along a
// lattice edge. The luma is what it is without, the chroma costs fewer
// bytes, and the points the next level has stay close to its samples.
TEST_P(MeshColorsModes, ChromaComesFromTheNextLevelsLattice) {
  // Mixed resolutions (every third face one step coarser), so that faces
  // sample finer edges.
  const enc::Image tex = ref::make_noise_texture(128, 11, 0x203040, 0xE0C060);
  enc::MeshColorsOptions mo;
  mo.max_res_log2 = 5;
  const size_t faces = test_colors().face_res.size();
  for (size_t f = 0; f < faces; ++f) mo.face_max_res.push_back(static_cast<uint8_t>(f % 3 == 0 ? 4 : 5));
  const enc::MeshColorsModel m = enc::to_mesh_colors(grid_model(4, tex), mo);
  ASSERT_EQ(m.max_res, 5);
  enc::MccOptions half, full;
  half.paper = full.paper = GetParam();
  full.chroma_half = false;
  half.chroma_half = true;
  const double quality = 0.25;
  const enc::MccEncoded eh = enc::encode_mesh_colors(m, quality, half), ef = enc::encode_mesh_colors(m, quality, full);
  EXPECT_EQ(eh.header[3] & mc::kFlagChromaHalf, mc::kFlagChromaHalf);
  EXPECT_EQ(ef.header[3] & mc::kFlagChromaHalf, 0);
  Held h;
  ASSERT_EQ(h.init(m.triangles, static_cast<uint32_t>(m.positions.size())), Status::ok);
  ASSERT_EQ(h.mc.set(m.face_res.data(), m.vertex_ycc.data(), 256), Status::ok);
  for (int level = 0; level < m.max_res; ++level) {
    EXPECT_LT(eh.level_bytes(level), ef.level_bytes(level)) << "level " << level;
    const auto ph = enc::decode_mesh_colors_level(m, eh, level), pf = enc::decode_mesh_colors_level(m, ef, level);
    EXPECT_EQ(ph[0], pf[0]) << "level " << level;
    h.mc.layout_level(level + 1);
    for (int c = 1; c < 3; ++c) {
      double err = 0;
      size_t count = 0;
      // A point the next level has: compared with its sample there.
      auto next_has = [&](uint32_t s, uint32_t t) {
        const double d = double(ph[c][s]) - m.levels[level + 1][c][t];
        err += d * d;
        ++count;
      };
      // Edges, on their own lattice (a face may sample a finer edge).
      const mc::Topology& topo = h.mc.topology();
      for (uint32_t e = 0; e < topo.edges; ++e) {
        const uint32_t R = mc::resolution(mc::level_res(h.mc.edge_res()[e], level));
        h.mc.layout_level(level + 1);
        const uint32_t next_base = h.mc.layout().edge_base + h.mc.layout().edge_offset[e] - 1;
        h.mc.layout_level(level);
        const uint32_t base = h.mc.layout().edge_base + h.mc.layout().edge_offset[e] - 1;  // + q, q = 1 .. R - 1
        auto at = [&](uint32_t q) {
          return q == 0 ? ph[c][topo.edge_vertex[2 * e]] : (q == R ? ph[c][topo.edge_vertex[2 * e + 1]] : ph[c][base + q]);
        };
        for (uint32_t q = 1; q < R; ++q) {
          if (q % 2 == 0) {
            next_has(base + q, next_base + q / 2);
          } else {
            ASSERT_EQ(at(q), (at(q - 1) + at(q + 1) + 1) / 2) << "level " << level << " edge " << e << " q " << q;
          }
        }
      }
      // Faces' own points.
      for (uint32_t f = 0; f < topo.faces; ++f) {
        const uint32_t R = mc::resolution(mc::level_res(m.face_res[f], level));
        for (uint32_t j = 1; j + 1 < R; ++j)
          for (uint32_t i = 1; i + j < R; ++i) {
            h.mc.layout_level(level);
            const uint32_t s = h.mc.sample_index(f, level, i, j);
            if (i % 2 == 0 && j % 2 == 0) {
              h.mc.layout_level(level + 1);
              next_has(s, h.mc.sample_index(f, level + 1, i / 2, j / 2));
              continue;
            }
            uint32_t a, b;
            if (j % 2 == 0) {
              a = h.mc.sample_index(f, level, i - 1, j);
              b = h.mc.sample_index(f, level, i + 1, j);
            } else if (i % 2 == 0) {
              a = h.mc.sample_index(f, level, i, j - 1);
              b = h.mc.sample_index(f, level, i, j + 1);
            } else {
              a = h.mc.sample_index(f, level, i - 1, j + 1);
              b = h.mc.sample_index(f, level, i + 1, j - 1);
            }
            ASSERT_EQ(ph[c][s], (ph[c][a] + ph[c][b] + 1) / 2)
                << "level " << level << " face " << f << " (" << i << ", " << j << ") component " << c;
          }
      }
      if (level + 1 < m.max_res) ASSERT_GT(count, 0u) << "level " << level;  // the last coded level fills only
      if (count == 0) continue;
      const double psnr = 10 * std::log10(255.0 * 255.0 * count / std::max(err, 1e-9));
      EXPECT_GE(psnr, 40.0) << "level " << level << " component " << c;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(PaperAndVds, MeshColorsModes, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& i) { return i.param ? "paper" : "vds"; });

// A model converted at R <= 16, coded at quality 1 and decoded: the finest
// level's luma within `min_db` of the model's.
void expect_round_trip(const enc::TexturedModel& t, double min_db) {
  enc::MeshColorsOptions o;
  o.max_res_log2 = 4;
  const enc::MeshColorsModel m = enc::to_mesh_colors(t, o);
  const enc::MccEncoded e = enc::encode_mesh_colors(m, 1);
  const auto planes = enc::decode_mesh_colors_level(m, e, 0);
  EXPECT_GE(plane_psnr(planes[0], m.levels[0][0]), min_db) << t.name;
}

// Real data: assimp-testmodels, which make test installs (scripts/fetch-data.sh).
TEST(MeshColorsImport, TheDuckAndMrFixitConvertAndRoundTrip) {
  const char* duck = "/usr/share/assimp/models/Collada/duck_triangulate.dae";
  const char* fixit = "/usr/share/assimp/models/IQM/mrfixit.iqm";
  for (const char* path : {duck, fixit})
    ASSERT_TRUE(std::ifstream(path).good()) << path << " not installed: scripts/fetch-data.sh installs assimp-testmodels";
  const enc::TexturedModel d = enc::load_textured_model(duck);
  EXPECT_EQ(d.positions.size(), 2108u);
  EXPECT_EQ(d.triangles.size(), 4212u);
  ASSERT_EQ(d.textures.size(), 1u);
  EXPECT_EQ(d.textures[0].width, 512);
  const enc::TexturedModel f = enc::load_textured_model(fixit);
  ASSERT_EQ(f.textures.size(), 2u);  // Body and Head, found by name with another extension
  EXPECT_GT(f.triangles.size(), 2000u);
  for (const enc::TexturedModel* t : {&d, &f}) expect_round_trip(*t, 34);  // mrfixit measured 35.5
}

std::vector<uint8_t> read_bytes(const char* path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
}

TEST(MeshColorsImport, IqmCountsThatDoNotFitAreRefusedNamingTheFile) {
  const char* fixit = "/usr/share/assimp/models/IQM/mrfixit.iqm";
  const std::vector<uint8_t> good = read_bytes(fixit);
  ASSERT_GT(good.size(), 124u) << fixit << " not installed";
  const std::string dir = std::string(::testing::TempDir()) + "/iqm_check";
  std::filesystem::create_directories(dir);
  auto refused = [&](std::vector<uint8_t> bytes, const std::string& want) {
    const std::string path = dir + "/bad.iqm";
    enc::write_file(path, bytes);
    try {
      enc::load_textured_model(path);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted: " << want;
  };
  auto set32 = [](std::vector<uint8_t>& b, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (8 * i));
  };
  std::vector<uint8_t> b = good;
  set32(b, 16 + 4 * 8, 0x10000000);  // num_vertexes
  refused(b, "do not fit");
  b = good;
  set32(b, 16 + 4 * 10, 0x40000000);  // num_triangles
  refused(b, "do not fit");
  b = good;
  b.resize(good.size() - 1);
  refused(b, "the header says the file is");
  b = good;
  set32(b, 16, 1);  // version
  refused(b, "IQM version 1");
}

// Quake II and MilkShape models: Sydney (an MD2 without skins, beside
// sydney.bmp) and the jeep (an MS3D naming ".\jeep1.jpg").
TEST(MeshColorsImport, Md2AndMs3dModelsConvertWithTheirImages) {
  const char* sydney = "/usr/share/assimp/models/MD2/sydney.md2";
  const char* jeep = "/usr/share/assimp/models/MS3D/jeep1.ms3d";
  for (const char* path : {sydney, jeep})
    ASSERT_TRUE(std::ifstream(path).good()) << path << " not installed: scripts/fetch-data.sh installs assimp-testmodels";
  const enc::TexturedModel s = enc::load_textured_model(sydney);
  EXPECT_EQ(s.triangles.size(), 679u);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].width, 308);  // the BMP beside it
  EXPECT_EQ(s.textures[0].height, 193);
  const enc::TexturedModel j = enc::load_textured_model(jeep);
  EXPECT_EQ(j.triangles.size(), 2032u);
  ASSERT_EQ(j.textures.size(), 1u);
  EXPECT_EQ(j.textures[0].width, 512);
  for (const enc::TexturedModel* t : {&s, &j}) expect_round_trip(*t, 34);
  // Alone in a folder, Sydney names no image that exists.
  const std::string dir = std::string(::testing::TempDir()) + "/md2_alone";
  std::filesystem::create_directories(dir);
  enc::write_file(dir + "/sydney.md2", read_bytes(sydney));
  try {
    enc::load_textured_model(dir + "/sydney.md2");
    ADD_FAILURE() << "a model whose image is missing was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("names no image, and no image beside the model has its name"), std::string::npos)
        << e.what();
  }
}

std::string model_refusal(const std::string& bytes, const std::string& name) {
  try {
    vds::enc::read_textured_model(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), name);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

void put(std::string& b, size_t at, uint32_t v, int n) {
  for (int i = 0; i < n; ++i) b[at + i] = static_cast<char>(v >> (8 * i));
}

TEST(MeshColorsImport, Md2CountsOffsetsAndIndicesThatLieAreRefusedNamingTheFile) {
  const std::vector<uint8_t> bytes = read_bytes("/usr/share/assimp/models/MD2/sydney.md2");
  ASSERT_GT(bytes.size(), 68u) << "assimp-testmodels not installed";
  const std::string good(bytes.begin(), bytes.end());
  // The valid file passes the check (from memory it stops at its image).
  EXPECT_EQ(model_refusal(good, "s.md2").find("(byte "), std::string::npos) << model_refusal(good, "s.md2");
  const uint32_t tris_at = static_cast<uint32_t>(bytes[52] | bytes[53] << 8);
  struct Lie {
    size_t at;
    uint32_t value;
    int bytes;
    const char* says;
  };
  const Lie lies[] = {
      {4, 9, 4, "s.md2: MD2 version 9 (8 is read) (byte 4)"},
      {40, 0, 4, "s.md2: frames 0 (1..512) (byte 40)"},
      {24, 3000, 4, "s.md2: vertices 3000 (1..2048) (byte 24)"},
      {8, 0, 4, "s.md2: skin width 0 (1..4096) (byte 8)"},
      {16, 100, 4, "s.md2: frame size (a frame of these vertices needs at least) 100"},
      {56, 300000, 4, "s.md2: the frames: 198 of 1408 bytes at offset 300000 do not fit the file's 302128 bytes (byte 56)"},
      {64, 302129, 4, "s.md2: the end offset 302129 lies outside the file's 302128 bytes (byte 64)"},
      {tris_at, 342, 2, "s.md2: triangle 0 names vertex 342 of 342"},
      {tris_at + 8, 456, 2, "s.md2: triangle 0 names texture coordinate 456 of 456"},
  };
  for (const Lie& l : lies) {
    std::string b = good;
    put(b, l.at, l.value, l.bytes);
    EXPECT_NE(model_refusal(b, "s.md2").find(l.says), std::string::npos) << model_refusal(b, "s.md2");
  }
  EXPECT_NE(model_refusal(good.substr(0, 5000), "s.md2").find("do not fit the file's 5000 bytes"), std::string::npos);
  // Every prefix (the header's every byte, then every 997th) is refused by the check, naming the file and a byte.
  for (size_t n = 0; n < good.size(); n += n < 200 ? 1 : 997) {
    const std::string r = model_refusal(good.substr(0, n), "s.md2");
    EXPECT_EQ(r.rfind("s.md2: ", 0), 0u) << "prefix " << n << ": " << r;
    if (n > 0) EXPECT_NE(r.find("(byte "), std::string::npos) << "prefix " << n << ": " << r;
  }
  EXPECT_NE(model_refusal("IDP2", "s.md2").find("not a Quake II model"), std::string::npos);
}

// A MilkShape model: three vertices, one triangle, one group naming
// `material`, `materials` materials, no joints; `tail` after.
std::string ms3d(int material, int materials, const std::string& tail = "") {
  auto le = [](uint32_t v, int n) {
    std::string s(static_cast<size_t>(n), '\0');
    for (int i = 0; i < n; ++i) s[static_cast<size_t>(i)] = static_cast<char>(v >> (8 * i));
    return s;
  };
  auto f32 = [&](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return le(u, 4);
  };
  std::string m = "MS3D000000" + le(4, 4) + le(3, 2);
  const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (const auto& v : p) m += std::string(1, '\0') + f32(v[0]) + f32(v[1]) + f32(v[2]) + le(0xFF, 1) + le(0, 1);
  m += le(1, 2);
  m += le(0, 2) + le(0, 2) + le(1, 2) + le(2, 2);                            // flags, the vertices
  for (int k = 0; k < 9; ++k) m += f32(k % 3 == 2 ? 1.0f : 0.0f);            // normals
  for (int k = 0; k < 6; ++k) m += f32(0.5f);                                // s, t
  m += le(1, 1) + le(0, 1);                                                  // smoothing group, group
  m += le(1, 2) + le(0, 1) + std::string(32, 'g') + le(1, 2) + le(0, 2) + le(static_cast<uint32_t>(material) & 0xFF, 1);
  m += le(static_cast<uint32_t>(materials), 2);
  for (int i = 0; i < materials; ++i) {
    std::string mat(361, '\0');
    mat[0] = 'm';
    for (int k = 0; k < 4; ++k) mat.replace(32 + 16 + 4 * k, 4, f32(0.8f));  // diffuse
    m += mat;
  }
  m += f32(24) + f32(0) + le(1, 4) + le(0, 2);  // animation, no joints
  return m + tail;
}

TEST(MeshColorsImport, Ms3dTablesThatLieAreRefusedNamingTheFile) {
  auto le = [](uint32_t v) {
    std::string s(4, '\0');
    for (int i = 0; i < 4; ++i) s[static_cast<size_t>(i)] = static_cast<char>(v >> (8 * i));
    return s;
  };
  // Valid: no material, one material, and the optional tables after.
  EXPECT_EQ(model_refusal(ms3d(-1, 0), "j.ms3d"), "");
  EXPECT_EQ(model_refusal(ms3d(0, 1), "j.ms3d"), "");
  const std::string tail = le(1) + le(0) + le(0) + le(0) + le(1) + le(2) + "hi" + le(3) + std::string(3 * 14, '\0') + le(1) +
                           le(1) + std::string(12, '\0');
  EXPECT_EQ(model_refusal(ms3d(-1, 0, tail), "j.ms3d"), "");
  EXPECT_NE(model_refusal(ms3d(1, 1), "j.ms3d").find("j.ms3d: a group names material 1 of 1"), std::string::npos);
  std::string b = ms3d(-1, 0);
  put(b, 16 + 45 + 2 + 2, 3, 2);  // the triangle's first vertex
  EXPECT_NE(model_refusal(b, "j.ms3d").find("j.ms3d: triangle 0 names vertex 3 of 3 (byte 65)"), std::string::npos)
      << model_refusal(b, "j.ms3d");
  b = ms3d(-1, 0);
  put(b, 16 + 45 + 2 + 70 + 2 + 33 + 2, 1, 2);  // the group's triangle
  EXPECT_NE(model_refusal(b, "j.ms3d").find("group 0 names triangle 1 of 1"), std::string::npos) << model_refusal(b, "j.ms3d");
  b = ms3d(-1, 0);
  put(b, 14, 40000, 2);  // vertices: their table runs past the end
  EXPECT_NE(model_refusal(b, "j.ms3d").find("the vertices: 600000 bytes, past the file's end"), std::string::npos)
      << model_refusal(b, "j.ms3d");
  b = ms3d(-1, 0);
  put(b, 10, 7, 4);
  EXPECT_NE(model_refusal(b, "j.ms3d").find("MS3D version 7"), std::string::npos);
  EXPECT_NE(model_refusal(ms3d(-1, 0, "xyz"), "j.ms3d").find("the comments' version: 4 bytes, past the file's end"),
            std::string::npos)
      << model_refusal(ms3d(-1, 0, "xyz"), "j.ms3d");
  EXPECT_NE(model_refusal(ms3d(-1, 0, tail + "x"), "j.ms3d").find("1 bytes after the model's last table"), std::string::npos);
  const std::string s = ms3d(-1, 0);
  for (size_t n = 0; n < s.size(); n += 7)
    EXPECT_NE(model_refusal(s.substr(0, n), "j.ms3d").find("j.ms3d: "), std::string::npos) << "prefix " << n;
}

}  // namespace

namespace {

std::string collada(const std::string& array_count, const std::string& accessor_count, const std::string& p) {
  return "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">"
         "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"" +
         array_count +
         "\">0 0 0 1 0 0 0 1 0</float_array><technique_common><accessor source=\"#pa\" count=\"" + accessor_count +
         "\" stride=\"3\"><param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/>"
         "<param name=\"Z\" type=\"float\"/></accessor></technique_common></source><vertices id=\"v\">"
         "<input semantic=\"POSITION\" source=\"#p\"/></vertices><triangles count=\"1\">"
         "<input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>" +
         p +
         "</p></triangles></mesh></geometry></library_geometries><library_visual_scenes><visual_scene id=\"s\"><node>"
         "<instance_geometry url=\"#g\"/></node></visual_scene></library_visual_scenes><scene>"
         "<instance_visual_scene url=\"#s\"/></scene></COLLADA>";
}

std::string refusal(const std::string& doc) {
  try {
    vds::enc::read_textured_model(reinterpret_cast<const uint8_t*>(doc.data()), doc.size(), "m.dae");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(MeshColorsImport, ColladaCountsAndIndicesThatLieAreRefusedNamingTheFile) {
  EXPECT_EQ(refusal(collada("9", "3", "0 1 2")), "");  // the valid document (no texture: untextured faces)
  EXPECT_NE(refusal(collada("0", "3", "0 1 2")).find("m.dae: <float_array count=\"0\"> holds 9 values"), std::string::npos);
  EXPECT_NE(refusal(collada("9", "4", "0 1 2")).find("an accessor of 4 x 3 from 0 in an array of 9"), std::string::npos);
  EXPECT_NE(refusal(collada("9", "3", "0 1 3")).find("index 3 names one of 3 elements"), std::string::npos);
  EXPECT_NE(refusal(collada("9", "3", "0 1")).find("holds 2 corners"), std::string::npos);
  EXPECT_NE(refusal(collada("9", "3", "0 1 -2")).find("is not a non-negative integer"), std::string::npos);
  EXPECT_NE(refusal(collada("99999999999", "3", "0 1 2")).find("is not a count"), std::string::npos);
  EXPECT_NE(refusal("<COLLADA><unclosed></COLLADA>").find("m.dae: not an XML document"), std::string::npos);
}

}  // namespace

namespace {

std::string le32s(uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[i] = static_cast<char>(v >> (8 * i));
  return s;
}

// A Quake III model: one frame, one surface of three vertices, one triangle.
std::string md3(uint32_t tri_index) {
  auto pad = [](std::string s, size_t n) {
    s.resize(n, '\0');
    return s;
  };
  const uint32_t surface_at = 108 + 56, tri = 108, st = tri + 12, xyz = st + 24, end = xyz + 24;
  std::string m = "IDP3" + le32s(15) + pad("t", 64) + le32s(0) + le32s(1) + le32s(0) + le32s(1) + le32s(0) + le32s(108) +
                  le32s(surface_at) + le32s(surface_at) + le32s(surface_at + end);
  m += std::string(56, '\0');
  m += "IDP3" + pad("s", 64) + le32s(0) + le32s(1) + le32s(0) + le32s(3) + le32s(1) + le32s(tri) + le32s(tri) +
       le32s(st) + le32s(xyz) + le32s(end);
  m += le32s(0) + le32s(1) + le32s(tri_index);
  m += std::string(24, '\0');  // texture coordinates
  const char xyzs[24] = {0, 0, 0, 0, 0, 0, 0, 0, 64, 0, 0, 0, 0, 0, 0, 0, 0, 0, 64, 0, 0, 0, 0, 0};
  m += std::string(xyzs, 24);
  return m;
}

std::string md3_refusal(const std::string& bytes) {
  try {
    vds::enc::read_textured_model(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), "p.md3");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(MeshColorsImport, Md3CountsAndIndicesThatLieAreRefusedNamingTheFile) {
  // The valid file passes the check (from memory it stops at its texture,
  // which it cannot open).
  EXPECT_EQ(md3_refusal(md3(2)).find("(byte "), std::string::npos) << md3_refusal(md3(2));
  EXPECT_NE(md3_refusal(md3(3)).find("p.md3: surface 0 triangle 0 names vertex 3 of 3"), std::string::npos);
  std::string b = md3(2);
  b.replace(76, 4, le32s(5000));  // frames
  EXPECT_NE(md3_refusal(b).find("frames 5000 (0..1024)"), std::string::npos);
  b = md3(2);
  b.replace(164 + 80, 4, le32s(4000));  // the surface's vertices: their table no longer fits
  EXPECT_NE(md3_refusal(b).find("do not fit the file"), std::string::npos);
  b = md3(2);
  b.replace(4, 4, le32s(16));
  EXPECT_NE(md3_refusal(b).find("MD3 version 16"), std::string::npos);
  EXPECT_NE(md3_refusal(md3(2).substr(0, 200)).find("p.md3: "), std::string::npos);
}

// openarena-data (scripts/fetch-data.sh): a player read straight from its
// archive is its legs, its torso on the legs' tag_torso and its head on
// the torso's tag_head, each with its skin's texture.
TEST(MeshColorsImport, AQuakePlayerIsItsThreePartsJoinedAtTheirTags) {
  const std::string pk3 = vds::enc::openarena_dir() + "/pak2-players.pk3";
  ASSERT_TRUE(std::ifstream(pk3).good()) << pk3 << " not installed: scripts/fetch-data.sh installs openarena-data";
  const vds::enc::TexturedModel m = vds::enc::load_textured_model(pk3 + ":models/players/major");
  EXPECT_EQ(m.positions.size(), 201u + 272u + 97u);  // lower, upper, head
  ASSERT_EQ(m.textures.size(), 3u);
  for (const std::string& f : m.texture_files) EXPECT_EQ(f.rfind(pk3 + ":models/players/major/", 0), 0u) << f;
  // Y up: from the legs' feet (lower.md3's frame 0 reaches 24.7 below its
  // origin) to the head's top (its tag_head 16.0 above the torso's, which
  // is 12.6 above the legs', and the head 6.8 above that).
  double lo = 1e9, hi = -1e9;
  for (const auto& p : m.positions) lo = std::min(lo, p[1]), hi = std::max(hi, p[1]);
  EXPECT_NEAR(lo, -24.7, 0.05);
  EXPECT_NEAR(hi, 12.57 + 15.99 + 6.78, 0.1);
  expect_round_trip(m, 30);
  // What is not a player is refused, by name.
  auto refusal = [](const std::string& path) {
    try {
      vds::enc::load_textured_model(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal(pk3 + ":models/players/nobody").find("the archive has no folder 'models/players/nobody'"), std::string::npos);
  const std::string dir = std::string(::testing::TempDir()) + "/md3_player";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  EXPECT_NE(refusal(dir).find("does not hold lower.md3, upper.md3 and head.md3"), std::string::npos) << refusal(dir);
  for (const char* part : {"lower", "upper", "head"}) {
    const std::string b = md3(2);
    vds::enc::write_file(dir + "/" + part + ".md3", std::vector<uint8_t>(b.begin(), b.end()));
  }
  EXPECT_NE(refusal(dir).find("lower.md3: has no tag_torso to join the player's next part to"), std::string::npos) << refusal(dir);
}

}  // namespace
