#!/bin/sh
# How the oak's stand-ins respond to the light, as the viewer draws them (issue 38):
# the mesh, the billboard cloud baked lit (the default) and baked unlit with normal maps,
# the volume at the defaults (normal moments, lit two-sided) and with --normals on (the
# mean normal, one-sided), each drawn headless by `billow view` under four lights (billow
# eval's standard set) from +x-y-z at 192x192, and compared with the mesh's picture by
# `billow compare` (coverage and mean covered luminance); then how each one's mean covered
# luminance changes from the overhead light to each other light, beside the mesh's.
# Usage: [SHADOWS=true] sh benches/relight.sh [BILLOW] [OUT_DIR]
set -e
B=${1:-target/release/billow}
D=${2:-out/relight}
SHADOWS=${SHADOWS:-false} # SHADOWS=true: the viewer's shadow maps on, for every picture
O=$(pwd)/fixtures/oak/eztree_oak_medium.gltf
mkdir -p "$D"
# One camera for every picture: the mesh's bounds framed from +x-y-z at 45° (as `billow
# eval` frames the mesh for the reference and the asset alike). `--view` would frame each
# scene's own content, and a volume's box (margin, alignment) is larger than the mesh's:
# the volume would be drawn about 9 % smaller.
CAM=$($B inspect "$O" --json | python3 -c "
import json, math, sys
b = json.load(sys.stdin)['bounds']
c = [(a + z) / 2 for a, z in zip(b['min'], b['max'])]
r = math.dist(b['min'], b['max']) / 2
d = r / math.sin(math.radians(45) / 2)
v = [1 / math.sqrt(3), -1 / math.sqrt(3), -1 / math.sqrt(3)]
print('--eye=%.6f,%.6f,%.6f --look-at=%.6f,%.6f,%.6f --fov 45' % (
    c[0] - d * v[0], c[1] - d * v[1], c[2] - d * v[2], c[0], c[1], c[2]))")
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
    printf '(light: (direction: (%s), ambient: 0.3), %s shadows: %s)\n' "$dir" "$content" "$SHADOWS" > "$D/s_$what.ron"
    $B view "$D/s_$what.ron" --headless --screenshot "$D/${name}_$what.png" --size 192x192 $CAM -q
  done
  for what in lit nm vol voln; do
    $B compare "$D/${name}_mesh.png" "$D/${name}_$what.png" --json | python3 -c "
import json, sys
e = json.load(sys.stdin)['error']
names = {'lit': 'cloud, baked lit', 'nm': 'cloud, unlit + normal maps', 'vol': 'volume, defaults (moments)', 'voln': 'volume, --normals on (mean)'}
print('| $name | %s | %.4f | %+.1f %% | %+.1f %% |' % (names['$what'], e['rmse'], 100 * e['coverage_rel_diff'], 100 * e['luminance_rel_diff']))"
  done
done
echo
echo "| light | mesh | cloud, baked lit | cloud, normal maps | volume, moments | volume, mean |"
echo "|---|---:|---:|---:|---:|---:|"
for name in sun-east sun-west below; do
  row="| overhead → $name"
  for what in mesh lit nm vol voln; do
    c=$($B compare "$D/overhead_mesh.png" "$D/overhead_$what.png" --json | python3 -c "import json, sys; print(json.load(sys.stdin)['error']['luminance_test'])")
    n=$($B compare "$D/overhead_mesh.png" "$D/${name}_$what.png" --json | python3 -c "import json, sys; print(json.load(sys.stdin)['error']['luminance_test'])")
    row="$row | $(python3 -c "print('%+.1f %%' % (100 * ($n / $c - 1)))")"
  done
  echo "$row |"
done
