#!/bin/sh
# One object, one look (issue 38, "Must show"): each mesh baked at the defaults as a volume
# and (foliage only) a billboard cloud, judged by `billow eval` against the ray-traced mesh
# under the standard light set (`--lights standard`: overhead, a low sun from either side,
# from below) at 1x, 4x, 16x and 64x the framed distance, six axis views, SIZE pixels,
# 16-spp reference; and the mesh itself drawn at 1 spp. Prints one markdown row per asset
# and distance: RMSE, FLIP, coverage and mean covered luminance against the mesh's (means
# over the views and the lights), and the RMSE under the asset's own bake light (what
# `billow eval` judged before the light set) with the ratio.
# Usage: sh benches/accuracy_lights.sh [BILLOW] [OUT_DIR] [MESH...]
# Meshes default to the bundled oak, the generated tree (examples/gen_fixtures, built here)
# and, when ../shared/assets is there, spot.
set -e
B=${1:-target/release/billow}
D=${2:-out/accuracy_lights}
SIZE=${SIZE:-128x128}
mkdir -p "$D"
shift 2 2>/dev/null || shift $#
if [ $# -eq 0 ]; then
  cargo run --release --locked -q --example gen_fixtures -- "$D/procedural" >/dev/null
  set -- fixtures/oak/eztree_oak_medium.gltf "$D/procedural/tree.obj"
  S=../shared/assets/spot_cow/spot.obj
  [ -f "$S" ] && set -- "$@" "$S"
fi
rows() { # NAME KIND LIGHTS_JSON BAKE_LIGHT_JSON
  python3 - "$@" <<'EOF'
import json, sys
name, kind, path, own_path = sys.argv[1:5]
def level(d):
    return d['levels'][0] if 'levels' in d else d  # a cloud: its LOD 0
d, own = level(json.load(open(path))), level(json.load(open(own_path)))
own_rmse = {m['distance_factor']: m['asset']['rmse'] for m in own['by_distance']}
raw = json.load(open(path))
for m in d['by_distance']:
    f, a = m['distance_factor'], m['asset']
    print('| %s | %s | %gx | %.4f | %.4f | %+.1f %% | %+.1f %% | %.4f | %.2f |' % (
        name, kind, f, a['rmse'], a['flip'], 100 * a['coverage_rel_diff'],
        100 * a['luminance_rel_diff'], own_rmse[f], a['rmse'] / max(own_rmse[f], 1e-12)))
# The mesh at 1 spp, once per mesh (the same in both files).
if kind == 'volume':
    for m in raw['by_distance']:
        r = m.get('raster_1spp')
        if r:
            print('| %s | mesh, 1 spp | %gx | %.4f | %.4f | %+.1f %% | %+.1f %% | | |' % (
                name, m['distance_factor'], r['rmse'], r['flip'],
                100 * r['coverage_rel_diff'], 100 * r['luminance_rel_diff']))
EOF
}
echo "| mesh | asset | distance | RMSE | FLIP | coverage | luminance | RMSE, bake light | ratio |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
for m in "$@"; do
  n=$(basename "$m"); n=${n%.*}
  $B voxelize "$m" -o "$D/$n.volume.billow" -q
  kinds=volume
  if $B bbcloud "$m" -o "$D/$n.cloud.billow" -q 2>/dev/null; then kinds="volume cloud"; fi
  for k in $kinds; do
    $B eval "$m" "$D/$n.$k.billow" --lights standard --distances 1,4,16,64 --size "$SIZE" --json > "$D/$n.$k.lights.json"
    $B eval "$m" "$D/$n.$k.billow" --distances 1,4,16,64 --size "$SIZE" --json > "$D/$n.$k.own.json"
    rows "$n" "$k" "$D/$n.$k.lights.json" "$D/$n.$k.own.json"
  done
done
