#!/bin/sh
# How the oak's stand-ins respond to the light, as the viewer draws them (issue 38):
# the mesh, the billboard cloud baked lit (the default) and baked unlit with normal maps,
# the volume at the defaults (no normals: unlit albedo) and with --normals on, each drawn
# headless by `billow view` under four lights (billow eval's standard set) from +x-y-z at
# 192x192, and compared with the mesh's picture by `billow compare` (coverage and mean
# covered luminance). Usage: sh benches/relight.sh [BILLOW] [OUT_DIR]
set -e
B=${1:-target/release/billow}
D=${2:-out/relight}
O=$(pwd)/fixtures/oak/eztree_oak_medium.gltf
mkdir -p "$D"
$B bbcloud "$O" -o "$D/lit.billow" -q
$B bbcloud "$O" -o "$D/nm.billow" --normal-map --unlit -q
$B voxelize "$O" -o "$D/vol.billow" -q
$B voxelize "$O" -o "$D/voln.billow" --normals on -q
echo "| light | stand-in | RMSE | coverage | mean covered luminance |"
echo "|---|---|---:|---:|---:|"
for light in "overhead 0,1,0" "sun-east 0.94,0.34,0.1" "sun-west -0.94,0.34,0.25" "below 0,-1,0"; do
  set -- $light; name=$1; dir=$2
  for what in mesh lit nm vol voln; do
    case $what in
      mesh) content="meshes: [(path: \"$O\")],";;
      vol|voln) content="volumes: [(asset: \"$(cd "$D" && pwd)/$what.billow\")],";;
      *) content="clouds: [(asset: \"$(cd "$D" && pwd)/$what.billow\", lod_distances: Some([0.001, 1000000.0, 2000000.0]), dissolve: 0.0)],";;
    esac
    printf '(light: (direction: (%s), ambient: 0.3), %s shadows: false)\n' "$dir" "$content" > "$D/s_$what.ron"
    $B view "$D/s_$what.ron" --headless --screenshot "$D/${name}_$what.png" --size 192x192 --view +x-y-z -q
  done
  for what in lit nm vol voln; do
    $B compare "$D/${name}_mesh.png" "$D/${name}_$what.png" --json | python3 -c "
import json, sys
e = json.load(sys.stdin)['error']
names = {'lit': 'cloud, baked lit', 'nm': 'cloud, unlit + normal maps', 'vol': 'volume, defaults', 'voln': 'volume, --normals on'}
print('| $name | %s | %.4f | %+.1f %% | %+.1f %% |' % (names['$what'], e['rmse'], 100 * e['coverage_rel_diff'], 100 * e['luminance_rel_diff']))"
  done
done
