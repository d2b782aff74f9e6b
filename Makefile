# billow — common jobs. `make demo` is the main job on the bundled sample; `make test` is
# the whole test suite (what CI runs). Both work on a fresh machine with only Rust installed.

CARGO   ?= cargo
BILLOW  := $(or $(CARGO_TARGET_DIR),target)/release/billow
SAMPLE  := fixtures/oak/eztree_oak_medium.gltf
OUT     ?= out

# Batch conversion: every mesh under IN_DIR becomes an asset under OUT_DIR (make -j safe:
# each output is its own target, written atomically by billow, and the binary is built once
# by the order-only prerequisite before any job starts).
IN_DIR  ?= fixtures
OUT_DIR ?= $(OUT)/batch
MESHES  := $(shell find $(IN_DIR) -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.obj' \) 2>/dev/null | grep -v ' ')
REPORTS := $(patsubst $(IN_DIR)/%,$(OUT_DIR)/%.inspect.json,$(MESHES))
VOLUMES := $(patsubst $(IN_DIR)/%,$(OUT_DIR)/%.volume.billow,$(MESHES))
BATCH_RES ?= 128

.PHONY: all build demo test lint fmt batch clean fixtures accuracy bench bench-bbcloud

all: build

build:
	$(CARGO) build --release --locked

$(BILLOW): build

## The main job on the bundled oak: inspect it, bake it into a volumetric billboard (plus a
## KTX2 copy), describe the asset, and render it next to a ray-traced reference (CPU renders
## in out/oak_eval/*.png, errors printed).
demo: build
	@mkdir -p $(OUT)
	$(BILLOW) inspect $(SAMPLE)
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/oak.billow --res 128 --ktx2 $(OUT)/oak.ktx2
	$(BILLOW) info $(OUT)/oak.billow
	$(BILLOW) eval $(SAMPLE) $(OUT)/oak.billow --views=+x+y+z,+x --distances 1,4 --size 256x256 --out $(OUT)/oak_eval

## The whole test suite: format, lint, unit + integration tests (also what .ci/run runs).
test:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --locked --workspace --all-targets -- -D warnings
	$(CARGO) test --locked --workspace

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --locked --workspace --all-targets -- -D warnings

fmt:
	$(CARGO) fmt --all

## Batch rule: `make -j2 batch IN_DIR=some/folder` maps every mesh in the folder to an
## import report (X.inspect.json) and a volume (X.volume.billow, --res BATCH_RES).
batch: $(REPORTS) $(VOLUMES)

$(OUT_DIR)/%.inspect.json: $(IN_DIR)/% | build
	@mkdir -p $(dir $@)
	$(BILLOW) inspect --json $< > $@.tmp && mv $@.tmp $@

$(OUT_DIR)/%.volume.billow: $(IN_DIR)/% | build
	@mkdir -p $(dir $@)
	$(BILLOW) voxelize -q --res $(BATCH_RES) $< -o $@

## Regenerate the procedural hard-case shapes (truss, furry torus, fur tile) as OBJ files.
fixtures:
	$(CARGO) run --release --example gen_fixtures -- $(OUT)/procedural

## Accuracy against cost: regenerates docs/accuracy.md and docs/accuracy/*.svg (a few
## minutes in release; Spot and the Bunny need ../shared/assets, skipped with a note otherwise).
accuracy:
	$(CARGO) run --release --locked --example accuracy -- docs/accuracy.md

clean:
	rm -rf $(OUT)

## Benchmark: `billow voxelize` vs. the raster floor on the 200k-triangle tree, side by side,
## medians of BENCH_RUNS runs at each of BENCH_RES; writes docs/benchmarks.md. Needs python3 and cc.
BENCH_SRC  ?= /work/shared/bench
BENCH_DIR  ?= $(OUT)/bench
BENCH_RES  ?= 128 256 512
BENCH_RUNS ?= 3
bench: build
	@mkdir -p $(BENCH_DIR)
	python3 $(BENCH_SRC)/gen_tree.py $(BENCH_DIR)/tree
	cc -O3 -march=native -o $(BENCH_DIR)/raster_floor $(BENCH_SRC)/raster_floor.c
	python3 benches/voxelize_bench.py --billow $(BILLOW) --floor $(BENCH_DIR)/raster_floor \
		--mesh $(BENCH_DIR)/tree.obj --res "$(BENCH_RES)" --runs $(BENCH_RUNS) \
		--notes benches/voxelize_bench_notes.md --out docs/benchmarks.md

## Benchmark: `billow bbcloud` on the oak (N = 500, ε = 0.04, defaults and a few options),
## medians of BBCLOUD_RUNS runs: wall and CPU time, billboards and atlas fill per LOD, stage
## times; writes docs/bbcloud_bench.md. Needs python3.
BBCLOUD_RUNS ?= 7
bench-bbcloud: build
	python3 benches/bbcloud_bench.py --billow $(BILLOW) --mesh $(SAMPLE) --runs $(BBCLOUD_RUNS) \
		--out docs/bbcloud_bench.md
