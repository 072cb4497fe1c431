// vds client library: the single build-time configuration header.
// Every option lists its legal values and what each costs on a Cortex-M4.
// Override any of them with -D on the compiler command line.
#pragma once

// Status names as strings (status_name()).
//   1: names compiled in, about 200 bytes of .rodata
//   0: status_name() returns "" (no strings in flash)
#ifndef VDS_CONFIG_STATUS_NAMES
#define VDS_CONFIG_STATUS_NAMES 1
#endif

// Error detail text inside the library (parsers' error_detail()): the text,
// or "" when status names are off, so the strings cost no flash either.
#if VDS_CONFIG_STATUS_NAMES
#define VDS_DETAIL(text) text
#else
#define VDS_DETAIL(text) ""
#endif

// CRC-32C implementation.
//  1024: four tables (slicing by 4), 4 KiB .rodata, about 3 instructions per byte
//   256: byte-wise table, 1 KiB .rodata, about 7 instructions per byte
//    16: nibble-wise table, 64 bytes .rodata, about 14 instructions per byte
#ifndef VDS_CONFIG_CRC32C_TABLE
#define VDS_CONFIG_CRC32C_TABLE 1024
#endif

// Canonical Huffman decoder: bits resolved by the first-level lookup table.
//   6..11: table of 2^N 16-bit entries in the caller's workspace (N=9: 1 KiB
//          per table); codes longer than N take a slower canonical walk
//          (about 6 extra instructions per extra bit).
#ifndef VDS_CONFIG_HUFF_LOOKUP_BITS
#define VDS_CONFIG_HUFF_LOOKUP_BITS 9
#endif

// Link (transport/core): out-of-order ranges a receiver tracks per reliable
// channel. A frame that would need one more range is dropped and resent.
//   4..32: 4 bytes of workspace per range per reliable receive channel;
//          16 keeps a 4 KiB window of ~40-byte frames (the size chosen at a
//          bit-error rate of 1e-3) fully usable.
#ifndef VDS_CONFIG_LINK_RX_RANGES
#define VDS_CONFIG_LINK_RX_RANGES 16
#endif

// Link: channel numbers a link endpoint can configure (0..N-1).
//   1..16: one pointer (4 bytes on Cortex-M) of Link state per channel;
//          channel buffers come from the caller's workspace.
#ifndef VDS_CONFIG_LINK_CHANNELS
#define VDS_CONFIG_LINK_CHANNELS 8
#endif

// Link: largest reliable window (receive buffer) of one channel, bytes.
//   1..16384: sequence numbers are 16-bit byte offsets, so a window must stay
//             well below 32 KiB for serial-number comparison to hold.
#ifndef VDS_CONFIG_LINK_MAX_WINDOW
#define VDS_CONFIG_LINK_MAX_WINDOW 16384
#endif

// Progressive mesh decoder: largest vertex degree (ring size) it handles.
// Streams declaring a larger one are refused (unsupported_feature).
//   16..1024: 16 bytes of workspace per unit (two ring scratches of vertex
//             and corner indices) plus about 25 bytes of stack per unit
//             while a split is decoded (candidate scores, ring prefix sums,
//             face scores); the split ranking costs O(degree^2) compares
//             per split in the worst case.
#ifndef VDS_CONFIG_MESH_MAX_DEGREE
#define VDS_CONFIG_MESH_MAX_DEGREE 64
#endif

// Renderer (vds/render.h): which formats have span loops compiled in. Each
// is a bit mask; a frame that asks for a format left out gets
// Status::unsupported_feature. Each texture x output x depth combination
// is a set of span loops (nearest and bilinear, repeat and clamp, with and
// without apron, vertex and view mapping): on Cortex-M4 (-O2) everything
// costs about 82 KiB of .text, rgb565 texture + rgb565 output + 16-bit depth
// alone about 23 KiB (bench/results/render.md). Speed is the same either way.
//   textures: 1 rgb565, 2 xrgb8888, 4 ycbcr420 (default 7: all)
//   outputs:  1 rgb565, 2 rgb888 (default 3)
//   depth:    1 16-bit, 2 32-bit (default 3)
#ifndef VDS_CONFIG_RENDER_TEXTURE_FORMATS
#define VDS_CONFIG_RENDER_TEXTURE_FORMATS 7
#endif
#ifndef VDS_CONFIG_RENDER_OUTPUT_FORMATS
#define VDS_CONFIG_RENDER_OUTPUT_FORMATS 3
#endif
#ifndef VDS_CONFIG_RENDER_DEPTH_FORMATS
#define VDS_CONFIG_RENDER_DEPTH_FORMATS 3
#endif

static_assert(VDS_CONFIG_CRC32C_TABLE == 1024 || VDS_CONFIG_CRC32C_TABLE == 256 || VDS_CONFIG_CRC32C_TABLE == 16,
              "VDS_CONFIG_CRC32C_TABLE must be 1024, 256 or 16");
static_assert(VDS_CONFIG_HUFF_LOOKUP_BITS >= 6 && VDS_CONFIG_HUFF_LOOKUP_BITS <= 11,
              "VDS_CONFIG_HUFF_LOOKUP_BITS must be 6..11");
static_assert(VDS_CONFIG_LINK_RX_RANGES >= 4 && VDS_CONFIG_LINK_RX_RANGES <= 32,
              "VDS_CONFIG_LINK_RX_RANGES must be 4..32");
static_assert(VDS_CONFIG_LINK_CHANNELS >= 1 && VDS_CONFIG_LINK_CHANNELS <= 16,
              "VDS_CONFIG_LINK_CHANNELS must be 1..16");
static_assert(VDS_CONFIG_LINK_MAX_WINDOW >= 1 && VDS_CONFIG_LINK_MAX_WINDOW <= 16384,
              "VDS_CONFIG_LINK_MAX_WINDOW must be 1..16384");
static_assert(VDS_CONFIG_MESH_MAX_DEGREE >= 16 && VDS_CONFIG_MESH_MAX_DEGREE <= 1024,
              "VDS_CONFIG_MESH_MAX_DEGREE must be 16..1024");
static_assert(VDS_CONFIG_RENDER_TEXTURE_FORMATS >= 1 && VDS_CONFIG_RENDER_TEXTURE_FORMATS <= 7,
              "VDS_CONFIG_RENDER_TEXTURE_FORMATS must be a non-empty mask of 1, 2, 4");
static_assert(VDS_CONFIG_RENDER_OUTPUT_FORMATS >= 1 && VDS_CONFIG_RENDER_OUTPUT_FORMATS <= 3,
              "VDS_CONFIG_RENDER_OUTPUT_FORMATS must be a non-empty mask of 1, 2");
static_assert(VDS_CONFIG_RENDER_DEPTH_FORMATS >= 1 && VDS_CONFIG_RENDER_DEPTH_FORMATS <= 3,
              "VDS_CONFIG_RENDER_DEPTH_FORMATS must be a non-empty mask of 1, 2");
