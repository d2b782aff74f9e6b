# billow — common jobs. `make demo` is the main job on the bundled sample; `make test` is
# the whole test suite (what CI runs). Both work on a fresh machine with only Rust installed.

CARGO   ?= cargo
BILLOW  := $(or $(CARGO_TARGET_DIR),target)/release/billow
SAMPLE  := fixtures/oak/eztree_oak_medium.gltf
OUT     ?= out

# The binary is a file target: built (`cargo build --release`) only when a source is newer
# than it. `make batch BILLOW=path/to/billow` uses that binary as it is, never building.
ifeq ($(origin BILLOW),command line)
BILLOW_SRC :=
else
BILLOW_SRC := $(shell find src bin formats/src viewer/src -type f 2>/dev/null) \
	Cargo.toml Cargo.lock formats/Cargo.toml viewer/Cargo.toml
endif

# Batch conversion: every mesh under IN_DIR becomes assets under OUT_DIR (make -j safe: each
# step of each mesh is its own target, written atomically by billow, and the binary is built
# once, as an order-only prerequisite, before any job starts). Each step writes a depfile
# (billow --depfile, included below) naming every file its bake looked for, found or not, so
# a changed buffer, texture or .mtl rebakes exactly the meshes that read it, a texture that
# was missing rebakes once it is there, and `make -q batch` is true after a batch. Paths make
# cannot hold (spaces, quotes, : % # $ \) are refused loudly.
IN_DIR  ?= fixtures
# `in/`, `in//` and `in` are one folder (the pattern rules below need it without the slash).
override IN_DIR := $(patsubst %/,%,$(patsubst %/,%,$(patsubst %/,%,$(IN_DIR))))
OUT_DIR ?= $(OUT)/batch
FOUND   := $(shell find $(IN_DIR) -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.obj' \) 2>/dev/null | sort)
UNSAFE  := $(shell find $(IN_DIR) -type f \( -name '*.gltf' -o -name '*.glb' -o -name '*.obj' \) 2>/dev/null | grep "[][ :%\#$$\\\"'()*?;&|<>\`]" | head -n 3)
ifneq ($(filter batch batch-outputs,$(MAKECMDGOALS)),)
ifeq ($(wildcard $(IN_DIR)/.),)
$(error batch: IN_DIR=$(IN_DIR) is not a folder (nothing was baked))
endif
ifeq ($(FOUND),)
$(error batch: no meshes (.gltf, .glb, .obj) under IN_DIR=$(IN_DIR) (nothing was baked))
endif
ifneq ($(UNSAFE),)
$(error batch: mesh paths under $(IN_DIR) with a space or another character make cannot handle, such as: $(UNSAFE); rename them (nothing was baked))
endif
endif
MESHES  := $(FOUND)
STEPS   := volume pruned cloud
STAMPS  := $(foreach s,$(STEPS),$(patsubst $(IN_DIR)/%,$(OUT_DIR)/%.$(s).done,$(MESHES)))
REPORTS := $(patsubst $(IN_DIR)/%,$(OUT_DIR)/%.inspect.json,$(MESHES))
BATCH_RES ?= 128
# Extra flags of each mesh's bakes (e.g. BATCH_VOXELIZE_ARGS='--preset quality').
BATCH_VOXELIZE_ARGS ?=
BATCH_CLOUD_ARGS ?=
# BATCH_STRICT=1: a warning (a missing texture, a skipped primitive) fails the mesh (billow --strict).
BATCH_STRICT ?=
# BATCH_KTX2=1 also writes X.volume.ktx2; BATCH_GLB=1 also writes X.cloud.glb (engine-ready copies).
BATCH_KTX2 ?=
BATCH_GLB ?=
STRICT  := $(if $(BATCH_STRICT),--strict)

.PHONY: all build demo test lint fmt batch batch-outputs clean fixtures accuracy accuracy-emptyspace accuracy-pareto bench bench-bbcloud gallery bench-view bench-particles check-gltf check-ktx2 check-threejs fuzz lod-sweep

all: build

# `make build` is the release binary (the CLI package; the library alone has no binary).
build: $(BILLOW)

$(BILLOW): $(BILLOW_SRC)
	$(CARGO) build --release --locked -p billow-cli
	@touch $@

## The main job on the bundled oak: bake it into a volumetric billboard (plus a KTX2 copy),
## prune the volume's empty space, bake it into a billboard cloud with 3 LODs (plus a .glb),
## compare volume and cloud with a ray-traced reference on the CPU (out/oak_eval/*.png), and
## render both side by side in the GPU viewer, headless (out/oak_view.png; installs Mesa's
## software Vulkan first when no adapter exists, like `make test`).
demo: $(BILLOW)
	@mkdir -p $(OUT)
	$(BILLOW) inspect $(SAMPLE)
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/oak.billow --res 128 --align 8 --ktx2 $(OUT)/oak.ktx2
	$(BILLOW) emptyspace $(OUT)/oak.billow -o $(OUT)/oak_pruned.billow
	$(BILLOW) bbcloud $(SAMPLE) -o $(OUT)/oak_cloud.billow --lods 3 --gltf $(OUT)/oak_cloud.glb
	$(BILLOW) info $(OUT)/oak_pruned.billow
	$(BILLOW) eval $(SAMPLE) $(OUT)/oak.billow --views=+x+y+z,+x --distances 1,4 --size 256x256 --out $(OUT)/oak_eval
	$(BILLOW) eval $(SAMPLE) $(OUT)/oak_cloud.billow --views=+x+y+z --distances 1,4 --size 256x256 --out $(OUT)/oak_cloud_eval
	printf '%s\n' '(camera: Some((eye: (0.0, 50.0, 190.0), target: (0.0, 28.0, 0.0), fov_deg: 45.0)),' \
		' volumes: [(asset: "oak_pruned.billow", instances: [(translate: (-60.0, 0.0, 0.0))])],' \
		' meshes: [(path: "$(CURDIR)/$(SAMPLE)")],' \
		' clouds: [(asset: "oak_cloud.billow", instances: [(translate: (60.0, 0.0, 0.0))])],' \
		' ground: Some((size: 240.0, color: (0.30, 0.36, 0.22))), shadows: true)' > $(OUT)/demo.ron
	sh .ci/ensure-vulkan
	$(BILLOW) view $(OUT)/demo.ron --headless --screenshot $(OUT)/oak_view.png --size 640x480 --background 0.55,0.62,0.72

## The whole test suite: format, lint, API docs without broken links, unit + integration
## tests (also what .ci/run runs).
## The viewer's tests render on a Vulkan adapter: .ci/ensure-vulkan installs Mesa's
## lavapipe when none is found; without one the suite stops here with the reason
## (BILLOW_ALLOW_NO_GPU=1 runs it anyway, the GPU tests then say they skip).
test:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --locked --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --locked --workspace --no-deps
	sh .ci/ensure-vulkan || [ -n "$$BILLOW_ALLOW_NO_GPU" ] || { \
		echo "make test: no Vulkan adapter and none could be installed (see above); set BILLOW_ALLOW_NO_GPU=1 to skip the GPU tests" >&2; exit 1; }
	NODEVICE_SELECT=1 $(CARGO) test --locked --workspace

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --locked --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --locked --workspace --no-deps

fmt:
	$(CARGO) fmt --all

## Batch rule: `make -j2 batch IN_DIR=some/folder` maps every mesh in the folder to an
## import report (X.inspect.json), a volume (X.volume.billow, --res BATCH_RES and
## BATCH_VOXELIZE_ARGS; X.volume.ktx2 with BATCH_KTX2=1), the volume with its empty space
## removed (X.pruned.billow) and a billboard cloud (X.cloud.billow, with BATCH_CLOUD_ARGS;
## X.cloud.glb with BATCH_GLB=1). Each step X.<step>.done records what it did ("done", or
## "skipped: REASON" for valid input with nothing to bake: a mesh without triangles, a cloud
## without foliage, whose message is kept in X.<step>.skipped); its warnings are kept in
## X.<step>.log, a failure's message in X.<step>.failed. One failed mesh does not stop the
## others (make -k); the batch ends with a summary (baked / skipped / failed / with warnings)
## and fails if any mesh failed. BATCH_STRICT=1 fails a mesh on any warning.
batch:
	+@$(MAKE) --no-print-directory -k batch-outputs; rc=$$?; \
	case '$(firstword -$(MAKEFLAGS))' in *[nqt]*) exit $$rc;; esac; \
	sh .ci/batch-summary '$(OUT_DIR)' '$(IN_DIR)' $(patsubst $(IN_DIR)/%,%,$(MESHES)); exit $$rc

batch-outputs: $(REPORTS) $(STAMPS)

-include $(wildcard $(addsuffix .d,$(STAMPS)) $(addsuffix .d,$(REPORTS)))

# A depfile's files that were missing when it was written: once one exists, billow's
# depfile makes its targets depend on this (always out of date) target.
.billow-restored:

# $(call batch_step,STAMP,DEPFILE,FALLBACK,OUTPUTS,COMMAND): .ci/batch-step's record of one step.
batch_step = sh .ci/batch-step '$(1)' '$(2)' '$(3)' '$(4)' -- $(5)

# The report depends on the files the volume's bake looked for (the same import).
$(OUT_DIR)/%.inspect.json: $(IN_DIR)/% $(OUT_DIR)/%.volume.done | $(BILLOW)
	@mkdir -p $(dir $@)
	$(BILLOW) inspect --json $< > $@.tmp && mv $@.tmp $@
	@if [ -f '$(OUT_DIR)/$*.volume.done.d' ]; then \
		sed '1s|.*|$@: \\|; s|^.*: \.billow-restored$$|$@: .billow-restored|' '$(OUT_DIR)/$*.volume.done.d' > '$@.d.tmp' && mv '$@.d.tmp' '$@.d'; \
	else rm -f '$@.d'; fi

$(OUT_DIR)/%.volume.done: $(IN_DIR)/% | $(BILLOW)
	@mkdir -p $(dir $@)
	@echo '$(BILLOW) voxelize $<'
	@$(call batch_step,$@,$(@:.done=.billow).d,,$(@:.done=.billow) $(@:.done=.ktx2),\
		$(BILLOW) voxelize --res $(BATCH_RES) --align 8 $(STRICT) $(BATCH_VOXELIZE_ARGS) \
		$(if $(BATCH_KTX2),--ktx2 $(@:.done=.ktx2)) $< -o $(@:.done=.billow) --depfile $(@:.done=.billow).d)

# Skipped with the volume it would prune.
$(OUT_DIR)/%.pruned.done: $(OUT_DIR)/%.volume.done | $(BILLOW)
	@echo '$(BILLOW) emptyspace $(<:.done=.billow)'
	@if grep -q '^skipped' $<; then rm -f $(@:.done=.billow) $@.d; echo 'skipped: no volume' > $@; else \
	$(call batch_step,$@,$(@:.done=.billow).d,,$(@:.done=.billow),\
		$(BILLOW) emptyspace $(<:.done=.billow) -o $(@:.done=.billow) --depfile $(@:.done=.billow).d); fi

# A cloud for every mesh with foliage (alpha MASK/BLEND materials); a mesh without any is
# skipped (bbcloud's exit code 9 and its reason in X.cloud.skipped), depending on the files
# the volume's bake looked for.
$(OUT_DIR)/%.cloud.done: $(IN_DIR)/% | $(BILLOW) $(OUT_DIR)/%.volume.done
	@mkdir -p $(dir $@)
	@echo '$(BILLOW) bbcloud $<'
	@$(call batch_step,$@,$(@:.done=.billow).d,$(OUT_DIR)/$*.volume.done.d,$(@:.done=.billow) $(@:.done=.glb),\
		$(BILLOW) bbcloud $(STRICT) $(BATCH_CLOUD_ARGS) $(if $(BATCH_GLB),--gltf $(@:.done=.glb)) \
		$< -o $(@:.done=.billow) --depfile $(@:.done=.billow).d)

## Regenerate the procedural hard-case shapes (truss, furry torus, fur tile) as OBJ files.
fixtures:
	$(CARGO) run --release --example gen_fixtures -- $(OUT)/procedural

## Accuracy against cost: regenerates docs/accuracy.md, docs/accuracy/*.svg and the quick
## headline numbers docs/accuracy/quick.md that tests/accuracy_drift.rs checks (a few
## minutes in release; Spot and the Bunny need ../shared/assets, skipped with a note otherwise).
accuracy:
	$(CARGO) run --release --locked --example accuracy -- docs/accuracy.md
	$(MAKE) accuracy-emptyspace
	$(MAKE) accuracy-pareto
	BILLOW_BLESS=1 $(CARGO) test --locked -p billow-cli --test accuracy_drift

## Empty-space removal: memory, render work and image change of `billow emptyspace` on the
## oak (128³, 256³) and Spot, and its --threshold / --min-box sweep; rewrites
## docs/emptyspace_sweep.md, the section of docs/accuracy.md between the emptyspace-sweep
## markers, and docs/accuracy/emptyspace.svg (about 2 minutes in release).
accuracy-emptyspace:
	$(CARGO) run --release --locked --example emptyspace_sweep -- --sweep-md docs/emptyspace_sweep.md --accuracy docs/accuracy.md

## Combined sweeps and Pareto fronts (resolution x supersampling x compression x slice
## spacing; epsilon x N x atlas size) on the oak, and the preset table (oak, a generated
## tree); rewrites docs/accuracy/pareto.md, docs/accuracy/pareto_*.svg and the section of
## docs/accuracy.md between the pareto markers (about 18 minutes on 2 cores, release, most of
## it counting bake instructions under callgrind; without valgrind about 5, with wall times).
accuracy-pareto:
	$(CARGO) run --release --locked --example pareto_sweep -- --md docs/accuracy/pareto.md --accuracy docs/accuracy.md

clean:
	rm -rf $(OUT)

## The gallery (docs/gallery.md): bakes the assets of fixtures/scenes/gallery/*.ron into
## fixtures/scenes/gallery/assets/ (not committed) and renders each scene headless into
## docs/gallery/*.png (lavapipe: tens of seconds per frame for the big scenes).
GALLERY := fixtures/scenes/gallery
GA      := $(GALLERY)/assets
GALLERY_SIZE ?= 640x480
gallery: build
	@mkdir -p $(GA) docs/gallery $(OUT)/procedural
	$(CARGO) run --release --locked --example gen_fixtures -- $(OUT)/procedural
	$(CARGO) run --release --locked --example gen_gallery -- $(GALLERY) 64 1200
	$(BILLOW) voxelize $(SAMPLE) -o $(GA)/oak128.billow --res 128 --combine mean -q
	$(BILLOW) voxelize $(SAMPLE) -o $(GA)/oak64.billow --res 64 --combine mean -q
	$(BILLOW) voxelize $(OUT)/procedural/truss.obj -o $(GA)/truss.billow --res 64x128x64 -q
	$(BILLOW) voxelize $(OUT)/procedural/furry_torus.obj -o $(GA)/furry_ball.billow --res 64 -q
	$(BILLOW) voxelize $(OUT)/procedural/fur_tile.obj -o $(GA)/fur_tile.billow --res 64 --bounds 0,0,0,1,1,1 -q
	cp $(OUT)/procedural/torus.obj $(OUT)/procedural/torus.mtl $(GA)/
	$(BILLOW) shell $(GA)/torus.obj $(GA)/fur_tile.billow -o $(GA)/furry_torus_shell.billow --height 0.25 --tiles 12,4 --surface-normals
	$(BILLOW) bbcloud $(SAMPLE) -o $(GA)/oak_cloud.billow --lods 4 -q
	sh .ci/ensure-vulkan
	for s in oak_trees field asteroid_belt furry_torus oak_clouds; do \
		$(BILLOW) view $(GALLERY)/$$s.ron --headless --screenshot docs/gallery/$$s.png \
			--size $(GALLERY_SIZE) || exit 1; done

## The viewer's performance (docs/performance.md, like the paper's Tables 1 and 2): plain
## uniform slicing vs adaptive vs adaptive + slab partitioning on the gallery's asteroid
## belt and furry torus, and frame time against resolution; on whatever adapter is found
## (lavapipe here). Needs `make gallery`'s assets.
bench-view: build
	python3 benches/view_bench.py --billow $(BILLOW) --scenes $(GALLERY) --out docs/performance.md

## Particle layer at full, 1/2, 1/4, 1/8 resolution on the explosion scene: frame times into
## docs/performance.md, image error against full into docs/accuracy.md (only the
## particle-layer sections), and the explosion pictures of docs/gallery.md. Needs python3.
bench-particles: build
	python3 benches/particle_layer_bench.py --billow $(BILLOW) --scene fixtures/scenes/explosion.ron \
		--pictures docs/gallery

## Benchmark: `billow voxelize` vs. the raster floor (benches/raster_floor.c) and OpenVDB's
## `vdb_tool -mesh2ls` (when installed: Debian's libopenvdb-tools) on the project's own
## 200k-triangle tree (examples/bench_tree.rs), side by side, medians of BENCH_RUNS runs at each
## of BENCH_RES, instruction counts (valgrind callgrind, when installed) at BENCH_COUNT_RES;
## BENCH_BEFORE=path/to/an/older/billow adds its rows. Writes docs/benchmarks.md. Needs python3 and cc.
BENCH_DIR  ?= $(OUT)/bench
BENCH_RES  ?= 128 256 512
BENCH_RUNS ?= 5
BENCH_COUNT_RES ?= 128
BENCH_BEFORE ?=
VDB_TOOL   ?= $(shell command -v vdb_tool)
bench: build
	@mkdir -p $(BENCH_DIR)
	$(CARGO) run --release --locked --example bench_tree -- $(BENCH_DIR)/tree.obj
	cc -O3 -march=native -o $(BENCH_DIR)/raster_floor benches/raster_floor.c
	cc -O3 -march=x86-64-v3 -o $(BENCH_DIR)/raster_floor_count benches/raster_floor.c
	python3 benches/voxelize_bench.py --billow $(BILLOW) --floor $(BENCH_DIR)/raster_floor \
		--count-floor $(BENCH_DIR)/raster_floor_count \
		--mesh $(BENCH_DIR)/tree.obj --res "$(BENCH_RES)" --runs $(BENCH_RUNS) \
		--callgrind-res "$(BENCH_COUNT_RES)" $(if $(VDB_TOOL),--vdb-tool $(VDB_TOOL)) \
		$(if $(BENCH_BEFORE),--before $(BENCH_BEFORE)) \
		--notes benches/voxelize_bench_notes.md --out docs/benchmarks.md

## Benchmark: `billow bbcloud` on the oak (N = 500, ε = 0.04, defaults and a few options),
## medians of BBCLOUD_RUNS runs: wall and CPU time, billboards and atlas fill per LOD, stage
## times; writes docs/bbcloud_bench.md. Needs python3.
BBCLOUD_RUNS ?= 7
bench-bbcloud: build
	python3 benches/bbcloud_bench.py --billow $(BILLOW) --mesh $(SAMPLE) --runs $(BBCLOUD_RUNS) \
		--out docs/bbcloud_bench.md

## $(call npm_package,NAME,VERSION): npm package NAME@VERSION installed once under $(OUT)/NAME.
npm_package = mkdir -p $(OUT)/$(1) && cd $(OUT)/$(1) && { [ -d node_modules/$(1) ] || \
	npm install --no-save --no-package-lock --silent $(1)@$(2); }

## The glTF exports checked by the Khronos glTF-Validator (needs Node.js and npm; the
## validator is installed under $(OUT)/gltf-validator): the oak's cloud as `make demo` bakes
## it, with normal maps and unlit, and with one LOD.
GLTF_VALIDATOR ?= 2.0.0-dev.3.10
check-gltf: build
	$(call npm_package,gltf-validator,$(GLTF_VALIDATOR))
	$(BILLOW) bbcloud $(SAMPLE) -o $(OUT)/gltf-validator/oak.billow --lods 3 --gltf $(OUT)/gltf-validator/oak.glb -q
	$(BILLOW) bbcloud $(SAMPLE) -o $(OUT)/gltf-validator/oak_nm.billow --lods 4 --normal-map --unlit \
		--gltf $(OUT)/gltf-validator/oak_nm.glb -q
	$(BILLOW) bbcloud $(SAMPLE) -o $(OUT)/gltf-validator/oak_1.billow --lods 1 \
		--gltf $(OUT)/gltf-validator/oak_1.glb -q
	NODE_PATH=$(OUT)/gltf-validator/node_modules node tests/gltf_validator/validate.js \
		$(OUT)/gltf-validator/oak.glb $(OUT)/gltf-validator/oak_nm.glb $(OUT)/gltf-validator/oak_1.glb

## LOD switches as a viewer sees them (docs/bbcloud.md, "LOD switches"): bakes the oak and a
## generated tree into 3-level clouds and sweeps their switches in the GPU viewer, on screen
## and at a constant fill: $(OUT)/lod_sweep/{oak,tree}{,_fill}/ (sweep.md, sweep.json,
## switch_K.png). Needs a Vulkan adapter (lavapipe is installed like for `make test`).
lod-sweep: build
	@mkdir -p $(OUT)/lod_sweep
	$(CARGO) run --release --locked --example gen_fixtures -- $(OUT)/procedural
	$(BILLOW) bbcloud $(SAMPLE) -o $(OUT)/lod_sweep/oak.billow --lods 3 -q
	$(BILLOW) bbcloud $(OUT)/procedural/tree.obj -o $(OUT)/lod_sweep/tree.billow --lods 3 -q
	sh .ci/ensure-vulkan
	for m in oak tree; do \
		NODEVICE_SELECT=1 $(BILLOW) view $(OUT)/lod_sweep/$$m.billow --lod-sweep $(OUT)/lod_sweep/$$m --size 400x400 --view=-z && \
		NODEVICE_SELECT=1 $(BILLOW) view $(OUT)/lod_sweep/$$m.billow --lod-sweep $(OUT)/lod_sweep/$${m}_fill --sweep-fill 0.9 --size 400x400 --view=-z || exit 1; \
	done

## The KTX2 exports read back by ktx-parse (the KTX2 reader three.js and glTF-Transform use;
## needs Node.js and npm, installed under $(OUT)/ktx-parse): header, DFD premultiplied flag,
## level sizes of the full MIP chain, on a cubic-ish and an odd non-cubic volume (BC7 blocks,
## --compress bc) and the odd one raw (--compress none, RGBA8); and the oak and the raw one
## again with --ktx2-zstd (Zstandard supercompression), each level inflated with zstddec (the
## decoder of three.js's KTX2Loader) and compared byte for byte with the plain file's.
KTX_PARSE ?= 2.0.0
ZSTDDEC ?= 0.1.0
check-ktx2: build
	mkdir -p $(OUT)/ktx-parse && cd $(OUT)/ktx-parse && { [ -d node_modules/ktx-parse ] && [ -d node_modules/zstddec ] || \
		npm install --no-save --no-package-lock --silent ktx-parse@$(KTX_PARSE) zstddec@$(ZSTDDEC); }
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/ktx-parse/oak.billow --res 128 --align 8 --compress bc --ktx2 $(OUT)/ktx-parse/oak.ktx2 -q
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/ktx-parse/oak_z.billow --res 128 --align 8 --compress bc --ktx2 $(OUT)/ktx-parse/oak_z.ktx2 --ktx2-zstd 19 -q
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/ktx-parse/odd.billow --res 45x17x30 --compress bc --ktx2 $(OUT)/ktx-parse/odd.ktx2 -q
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/ktx-parse/raw.billow --res 45x17x30 --compress none --ktx2 $(OUT)/ktx-parse/raw.ktx2 -q
	$(BILLOW) voxelize $(SAMPLE) -o $(OUT)/ktx-parse/raw_z.billow --res 45x17x30 --compress none --ktx2 $(OUT)/ktx-parse/raw_z.ktx2 --ktx2-zstd 3 -q
	node tests/ktx2_reader/check.mjs $(OUT)/ktx-parse/node_modules $(OUT)/ktx-parse/oak.ktx2 $(OUT)/ktx-parse/odd.ktx2 $(OUT)/ktx-parse/raw.ktx2 \
		$(OUT)/ktx-parse/oak_z.ktx2=$(OUT)/ktx-parse/oak.ktx2 $(OUT)/ktx-parse/raw_z.ktx2=$(OUT)/ktx-parse/raw.ktx2

## The oak's cloud export rendered by a real glTF client: three.js (GLTFLoader) in headless
## Chromium (Debian's chromium, driven by playwright-core; WebGL on SwiftShader, no network)
## against billow's CPU cloud renderer from the same camera, compared with `billow compare`
## within a stated RMSE and coverage tolerance (tests/threejs/check.sh, docs/bbcloud.md).
## Needs Node.js, npm (three and playwright-core installed under $(OUT)) and chromium
## (installed with apt-get when missing and run as root); otherwise it prints
## `SKIP: check-threejs: ...` and succeeds, unless BILLOW_REQUIRE=all.
## `make check-threejs FIGURE=docs/bbcloud/threejs_oak.png` also updates the docs' picture.
THREE ?= 0.187.0
PLAYWRIGHT_CORE ?= 1.65.1
check-threejs: build
	BILLOW=$(BILLOW) CARGO=$(CARGO) OUT=$(OUT) THREE=$(THREE) PLAYWRIGHT_CORE=$(PLAYWRIGHT_CORE) \
		FIGURE=$(FIGURE) sh tests/threejs/check.sh

## Coverage-guided fuzzing (docs/robustness.md, "Fuzzing"): runs each target of fuzz/ in
## turn for FUZZ_TIME seconds with cargo-fuzz on the nightly toolchain
## (`cargo install cargo-fuzz --locked`). New inputs land in fuzz/corpus/<target>/, crashes
## in fuzz/artifacts/<target>/. CI does not fuzz: `cargo test -p billow-cli --test fuzz_corpus_replay`
## replays the committed corpora.
FUZZ_TARGETS ?= asset_reader gltf_import obj_import combine_expr scene_ron
FUZZ_TIME    ?= 600
fuzz:
	for t in $(FUZZ_TARGETS); do \
		ASAN_OPTIONS=detect_odr_violation=0 $(CARGO) +nightly fuzz run $$t -- -max_total_time=$(FUZZ_TIME) -timeout=10 \
			-rss_limit_mb=2048 -malloc_limit_mb=1024 || exit 1; \
	done
