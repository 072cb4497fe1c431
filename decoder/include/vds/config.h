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

// CRC-32C implementation.
//   256: byte-wise table, 1 KiB .rodata, about 7 instructions per byte
//    16: nibble-wise table, 64 bytes .rodata, about 14 instructions per byte
#ifndef VDS_CONFIG_CRC32C_TABLE
#define VDS_CONFIG_CRC32C_TABLE 256
#endif

// Canonical Huffman decoder: bits resolved by the first-level lookup table.
//   6..11: table of 2^N 16-bit entries in the caller's workspace (N=9: 1 KiB
//          per table); codes longer than N take a slower canonical walk
//          (about 6 extra instructions per extra bit).
#ifndef VDS_CONFIG_HUFF_LOOKUP_BITS
#define VDS_CONFIG_HUFF_LOOKUP_BITS 9
#endif

static_assert(VDS_CONFIG_CRC32C_TABLE == 256 || VDS_CONFIG_CRC32C_TABLE == 16,
              "VDS_CONFIG_CRC32C_TABLE must be 256 or 16");
static_assert(VDS_CONFIG_HUFF_LOOKUP_BITS >= 6 && VDS_CONFIG_HUFF_LOOKUP_BITS <= 11,
              "VDS_CONFIG_HUFF_LOOKUP_BITS must be 6..11");
