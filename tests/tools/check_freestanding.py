#!/usr/bin/env python3
"""Link check of the client parts on the Cortex-M build (soft-float ABI).

Fails if anything in the client libraries references a floating-point helper,
the heap, exception support, or any C library function beyond
memcpy/memset/memmove; then links every object of the libraries into one
image with -nostdlib (only libgcc's integer helpers and a three-function
memory shim available), so any other reference is an undefined symbol.
Prints .text/.rodata/.data/.bss per component.
"""
import argparse
import os
import re
import subprocess
import sys

ALLOWED_LIBC = {"memcpy", "memset", "memmove"}
# Run-time ABI helpers the compiler emits for integer work and memory moves.
ALLOWED_ABI = re.compile(
    r"^(__aeabi_(memcpy|memcpy4|memcpy8|memset|memset4|memset8|memclr|memclr4|memclr8|memmove|memmove4|memmove8"
    r"|uldivmod|ldivmod|idiv|uidiv|idivmod|uidivmod|llsl|llsr|lasr|lmul|lcmp|ulcmp)"
    r"|__(clz|ctz|popcount|ffs|parity|bswap)[sd]i2"
    r"|__(u?divmoddi4|u?divdi3|u?moddi3|ashldi3|ashrdi3|lshrdi3|muldi3|cmpdi2|ucmpdi2))$")
FLOAT = re.compile(r"^(__aeabi_([fd](add|sub|rsub|mul|div|neg|cmp|cmpeq|cmplt|cmple|cmpge|cmpgt|cmpun|2)"
                   r"|[iul]+2[fd]|f2|d2)|__[a-z]*(sf|df|tf|xf|hf)[0-9a-z]*$)")
HEAP = re.compile(r"^(malloc|calloc|realloc|free|aligned_alloc|posix_memalign|_sbrk|sbrk"
                  r"|_Zn[wa][jmy].*|_Zd[la]Pv.*)$")
EXCEPTIONS = re.compile(r"^(__cxa_.*|_Unwind_.*|__gxx_personality.*|__aeabi_unwind_cpp_pr.*|_ZTI.*|_ZTS.*|__cxa_pure_virtual)$")

SHIM = r"""
/* Memory shim for the link check: the only C library the client may use. */
typedef unsigned int size_t;
void* memcpy(void* d, const void* s, size_t n) { unsigned char* o = (unsigned char*)d; const unsigned char* i = (const unsigned char*)s; while (n--) *o++ = *i++; return d; }
void* memmove(void* d, const void* s, size_t n) { unsigned char* o = (unsigned char*)d; const unsigned char* i = (const unsigned char*)s; if (o < i) { while (n--) *o++ = *i++; } else { o += n; i += n; while (n--) *--o = *--i; } return d; }
void* memset(void* d, int c, size_t n) { unsigned char* o = (unsigned char*)d; while (n--) *o++ = (unsigned char)c; return d; }
void _start(void) { for (;;) {} }
"""


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def symbols(nm, path, flag):
    code, out, err = run([nm, flag, path])
    if code != 0:
        sys.exit(f"link check: {nm} {flag} {path} failed: {err.strip()}")
    names = set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and not line.endswith(":"):
            names.add(parts[-1])
    return names


def defined(nm, path):
    code, out, err = run([nm, "--defined-only", path])
    if code != 0:
        sys.exit(f"link check: {nm} {path} failed: {err.strip()}")
    return {l.split()[-1] for l in out.splitlines() if len(l.split()) >= 3}


def section_sizes(size_tool, path):
    code, out, err = run([size_tool, "-A", path])
    if code != 0:
        sys.exit(f"link check: {size_tool} {path} failed: {err.strip()}")
    sums = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) < 2 or not parts[1].isdigit():
            continue
        name, sz = parts[0], int(parts[1])
        for key in sums:
            if name == "." + key or name.startswith("." + key + "."):
                sums[key] += sz
    return sums


BAD_SOURCE = r"""
// Deliberate violations: the check must name each one.
#include <cstdlib>
#include <cstdio>
extern "C" int uses_float(int a) { volatile float f = static_cast<float>(a); return static_cast<int>(f * 1.5f); }
extern "C" int uses_double(int a) { volatile double d = a; return static_cast<int>(d / 3.0); }
extern "C" void* uses_heap(unsigned n) { return std::malloc(n); }
extern "C" int uses_libc(int a) { return std::printf("%d", a); }
int* uses_new() { return new int(3); }
"""


def self_test(a):
    """Builds a library with known violations and checks each is reported."""
    src = os.path.join(a.out, "violations.cpp")
    obj = os.path.join(a.out, "violations.o")
    lib = os.path.join(a.out, "libviolations.a")
    with open(src, "w") as f:
        f.write(BAD_SOURCE)
    code, _, err = run([a.cxx, f"-mcpu={a.cpu}", "-mthumb", "-mfloat-abi=soft", "-O2", "-fno-exceptions",
                        "-fno-rtti", "-c", src, "-o", obj])
    if code != 0:
        sys.exit("self-test: cannot compile the violations: " + err)
    ar = a.cxx.replace("g++", "ar")
    if os.path.exists(lib):
        os.remove(lib)
    code, _, err = run([ar, "rcs", lib, obj])
    if code != 0:
        sys.exit("self-test: cannot archive: " + err)
    failures = check_libs(a, [("violations", lib)], stem="violations")
    report = "\n".join(failures)
    expected = ["__aeabi_fmul (floating-point helper)", "(floating-point helper)", "malloc (heap)",
                "printf (C library", "(heap)", "with -nostdlib failed"]
    missing = [e for e in expected if e not in report]
    for needle in ["__aeabi_d", "__aeabi_f", "_Znw"]:
        if needle not in report:
            missing.append(needle)
    print(report)
    if missing:
        print("self-test FAILED: not reported: " + ", ".join(missing))
        return 1
    print("self-test: every deliberate violation was reported")
    return 0


def check_libs(a, libs, stem="client"):
    failures = []
    all_defined = set()
    for _, path in libs:
        all_defined |= defined(a.nm, path)
    for name, path in libs:
        for sym in sorted(symbols(a.nm, path, "-u") - all_defined):
            if sym in ALLOWED_LIBC or ALLOWED_ABI.match(sym):
                continue
            if FLOAT.match(sym):
                kind = "floating-point helper"
            elif HEAP.match(sym):
                kind = "heap"
            elif EXCEPTIONS.match(sym):
                kind = "exception/RTTI support"
            else:
                kind = "C library or other outside symbol"
            failures.append(f"{name}: references {sym} ({kind})")

    # The real link: every object, no C library, no start files.
    shim_c = os.path.join(a.out, "memshim.c")
    with open(shim_c, "w") as f:
        f.write(SHIM)
    elf = os.path.join(a.out, f"{stem}_linkcheck.elf")
    mapfile = os.path.join(a.out, f"{stem}_linkcheck.map")
    if os.path.exists(elf):
        os.remove(elf)
    cmd = [a.cxx, f"-mcpu={a.cpu}", "-mthumb", "-mfloat-abi=soft", "-O2", "-ffreestanding", "-fno-builtin",
           "-nostdlib", "-x", "c", shim_c, "-x", "none", "-Wl,--whole-archive"] + [p for _, p in libs] + \
          ["-Wl,--no-whole-archive", "-lgcc", f"-Wl,-Map={mapfile}", "-o", elf]
    code, out, err = run(cmd)
    if code != 0:
        failures.append("link of every client object with -nostdlib failed:\n" + err.strip())
    else:
        for sym in sorted(defined(a.nm, elf)):
            if FLOAT.match(sym):
                failures.append(f"linked image pulls in floating-point helper {sym}")
            elif HEAP.match(sym) or EXCEPTIONS.match(sym):
                failures.append(f"linked image contains {sym}")

    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--self-test", action="store_true", help="check that known violations are caught")
    ap.add_argument("--cxx", required=True)
    ap.add_argument("--nm", required=True)
    ap.add_argument("--size", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--lib", action="append", default=[], help="NAME=path/to/lib.a")
    ap.add_argument("--cpu", default="cortex-m4")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)

    if a.self_test:
        return self_test(a)
    if not a.lib:
        sys.exit("link check: give at least one --lib NAME=path")
    libs = []
    for spec in a.lib:
        name, _, path = spec.partition("=")
        if not os.path.exists(path):
            sys.exit(f"link check: {name}: {path} does not exist (was the Cortex-M4 sub-build built?)")
        libs.append((name, path))

    failures = check_libs(a, libs)
    elf = os.path.join(a.out, "client_linkcheck.elf")
    linked = os.path.exists(elf)

    print(f"Client size on {a.cpu} (bytes, from the Cortex-M objects):")
    print(f"  {'component':<16} {'.text':>8} {'.rodata':>8} {'.data':>8} {'.bss':>8}")
    total = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    for name, path in libs:
        s = section_sizes(a.size, path)
        for k in total:
            total[k] += s[k]
        print(f"  {name:<16} {s['text']:>8} {s['rodata']:>8} {s['data']:>8} {s['bss']:>8}")
    print(f"  {'total':<16} {total['text']:>8} {total['rodata']:>8} {total['data']:>8} {total['bss']:>8}")
    if linked:
        s = section_sizes(a.size, elf)
        print(f"  {'linked image':<16} {s['text']:>8} {s['rodata']:>8} {s['data']:>8} {s['bss']:>8}"
              "  (every object kept, no garbage collection)")

    if failures:
        print("\nFREESTANDING RULES BROKEN:")
        for f in failures:
            print("  " + f)
        return 1
    print("\nlink check: no float, heap, exception or C library reference beyond memcpy/memset/memmove")
    return 0


if __name__ == "__main__":
    sys.exit(main())
