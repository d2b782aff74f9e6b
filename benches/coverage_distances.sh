#!/bin/sh
# Coverage at every distance (issue 38, item 3): each mesh baked as a volume (`opaque` and
# `mean` combines, every preset) and as a billboard cloud (every preset, LOD 0), each
# judged by `billow eval` against the ray-traced mesh over the six axis views at 1x, 4x,
# 16x and 64x the framed distance (SIZE pixels, 16-spp reference). Prints one markdown
# row per asset: the signed coverage difference against the mesh at each distance, and
# the RMSE at 1x.
# Usage: sh benches/coverage_distances.sh [BILLOW] [OUT_DIR] [MESH...]
# Meshes default to the bundled oak, the generated tree (examples/gen_fixtures, built
# here) and, when ../shared/assets is there, the ez-tree flowers.
set -e
B=${1:-target/release/billow}
D=${2:-out/coverage}
SIZE=${SIZE:-128x128}
PRESETS=${PRESETS:-draft balanced quality hero}
COMBINES=${COMBINES:-opaque mean}
mkdir -p "$D"
shift 2 2>/dev/null || shift $#
if [ $# -eq 0 ]; then
  cargo run --release --locked -q --example gen_fixtures -- "$D/procedural" >/dev/null
  set -- fixtures/oak/eztree_oak_medium.gltf "$D/procedural/tree.obj"
  F=../shared/assets/eztree_flowers/flower_white.glb
  [ -f "$F" ] && set -- "$@" "$F"
fi
row() { # NAME KIND SETTINGS JSON
  python3 - "$@" <<'EOF'
import json, sys
name, kind, settings, path = sys.argv[1:5]
d = json.load(open(path))
if 'by_distance' not in d:
    d = d['levels'][0]  # a cloud: its LOD 0
cov = {m['distance_factor']: m['asset']['coverage_rel_diff'] for m in d['by_distance']}
rmse = {m['distance_factor']: m['asset']['rmse'] for m in d['by_distance']}
cells = ' | '.join('%+.1f %%' % (100 * cov[f]) for f in sorted(cov))
print('| %s | %s | %s | %s | %.4f |' % (name, kind, settings, cells, rmse[min(rmse)]))
EOF
}
echo "| mesh | asset | settings | coverage 1x | 4x | 16x | 64x | RMSE 1x |"
echo "|---|---|---|---:|---:|---:|---:|---:|"
for m in "$@"; do
  n=$(basename "$m"); n=${n%.*}
  for c in $COMBINES; do
    for p in $PRESETS; do
      if [ -z "$CLOUDS_ONLY" ]; then
      $B voxelize "$m" -o "$D/$n.$c.$p.billow" --preset "$p" --combine "$c" -q
      $B eval "$m" "$D/$n.$c.$p.billow" --distances 1,4,16,64 --size "$SIZE" --json > "$D/$n.$c.$p.json"
      row "$n" volume "$c, $p" "$D/$n.$c.$p.json"
      fi
    done
  done
  for p in $PRESETS; do
    if $B bbcloud "$m" -o "$D/$n.cloud.$p.billow" --preset "$p" -q 2>"$D/$n.cloud.$p.err"; then
      $B eval "$m" "$D/$n.cloud.$p.billow" --distances 1,4,16,64 --size "$SIZE" --json > "$D/$n.cloud.$p.json"
      row "$n" cloud "$p" "$D/$n.cloud.$p.json"
    else
      echo "| $n | cloud | $p | $(head -1 "$D/$n.cloud.$p.err") |||||"
    fi
  done
done
