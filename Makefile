# The README's two commands. Each does its own set-up on a fresh Debian machine.
.PHONY: demo test setup data build-test build-release bench fuzz clean

JOBS ?= 2

setup:
	bash scripts/setup.sh

# The sample content (Debian packages): glmark2 models and textures,
# OpenArena textures. Tests use it when present (real-data conformance).
data:
	bash scripts/fetch-data.sh

build-test: setup
	cmake --preset host
	cmake --build --preset host -j $(JOBS)

build-release: setup
	cmake --preset host-release
	cmake --build --preset host-release -j $(JOBS)

## make test: install, build (host under sanitizers + Cortex-M4), run every test
test: build-test data
	ctest --preset host

## make demo: install, build, fetch sample data, encode, stream, report
demo: build-release data
	bash scripts/demo.sh build/host-release

## make bench: the benchmarks against the anchors (slow; writes bench/results/)
bench: build-release data
	bash bench/run_all.sh build/host-release

## make fuzz: long libFuzzer runs (FUZZ_SECONDS each)
FUZZ_SECONDS ?= 300
fuzz: setup
	cmake --preset host -DVDS_FUZZ_SECONDS=$(FUZZ_SECONDS)
	cmake --build --preset host -j $(JOBS)
	ctest --preset host -R '^fuzz_'

clean:
	rm -rf build
