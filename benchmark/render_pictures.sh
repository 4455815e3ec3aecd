#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Makes the pictures of the README (doc/fig/*.png) with render_cloud and prints the wrong
# normals of each, as a Markdown table.
#
#   bash benchmark/render_pictures.sh BUILD_DIR [--mesh MESH.off] [--points N] [--noise F]
#        [--seed S] [--large-points N] [--size PIXELS] [--view AZ,EL] [--out DIR]
#
# BUILD_DIR holds the programs (configured with the benchmarks and the examples):
#   cmake --build BUILD_DIR -j2 --target make_cloud make_large_cloud cgal_mst_orient \
#         count_wrong_normals render_cloud orient_normals
#
# 1. make_cloud samples N points on the mesh (default: armadillo, 30,000 points, Gaussian
#    noise F = 0.002 x bbox diagonal, seed 1): PCA normals with random signs;
# 2. the cloud is oriented by orient_normals --solver mst, by orient_normals (default solver,
#    MST + QPBO-I) and by CGAL::mst_orient_normals (cgal_mst_orient);
# 3. count_wrong_normals counts the wrong normals of each (dot with the outward normal of the
#    closest mesh triangle <= 0);
# 4. render_cloud draws: the input (random signs) and our default output with one-sided
#    shading (before / after), and the three outputs with the wrong normals in red;
# 5. make_large_cloud samples a larger cloud (default 300,000 points), orient_normals
#    --stream --write-segments orients it out of core, and render_cloud colours its points by
#    segment.
# The pictures are SIZE x SIZE pixels (default 600), 5 bits per channel (smaller files).
# Everything is deterministic: the same options give the same pictures and counts.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
usage() { sed -n '5,6p' "$0" | sed 's/^# *//' >&2; exit 2; }
[ $# -ge 1 ] || usage
build=$(realpath "$1"); shift
mesh="$here/../../shared/data/meshes/armadillo.off"
points=30000
noise=0.002
seed=1
large_points=300000
size=600
view=200,15
out="$here/../doc/fig"
while [ $# -gt 0 ]; do
  case "$1" in
    --mesh) mesh="$2"; shift 2 ;;
    --points) points="$2"; shift 2 ;;
    --noise) noise="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --large-points) large_points="$2"; shift 2 ;;
    --size) size="$2"; shift 2 ;;
    --view) view="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) echo "render_pictures.sh: unknown option '$1'" >&2; usage ;;
  esac
done

make_cloud="$build/benchmark/make_cloud"
make_large_cloud="$build/benchmark/make_large_cloud"
cgal="$build/benchmark/cgal_mst_orient"
count="$build/benchmark/count_wrong_normals"
render="$build/benchmark/render_cloud"
ours="$build/examples/orient_normals"
for program in "$make_cloud" "$make_large_cloud" "$cgal" "$count" "$render" "$ours"; do
  if [ ! -x "$program" ]; then
    echo "render_pictures.sh: missing $program (build it, see the header of this script)" >&2
    exit 1
  fi
done
[ -f "$mesh" ] || { echo "render_pictures.sh: no mesh '$mesh'" >&2; exit 1; }
mkdir -p "$out"
out=$(realpath "$out")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
name=$(basename "$mesh" .off)

# the wrong normals of CLOUD as "W (P%)"
wrong() {
  "$count" --json "$mesh" "$1" 2> /dev/null |
    sed -n 's/.*"wrong": \([0-9]*\), "wrong_percent": \([0-9.]*\).*/\1 (\2%)/p' |
    awk '{ printf "%s (%.3g%%)", $1, substr($2, 2) + 0 }'
}
picture() { # CLOUD NAME [render_cloud options...]
  local cloud="$1" file="$out/$2.png"; shift 2
  "$render" --quiet --width "$size" --height "$size" --view "$view" --bits 5 "$@" "$cloud" "$file"
  printf '%s' "$file"
}
kb() { echo "$(( ($(wc -c < "$1") + 1023) / 1024 )) KB"; }

echo "render_pictures.sh: $points points on $name, noise $noise, seed $seed" >&2
"$make_cloud" "$mesh" "$points" "$work/cloud" --noise "$noise" --seed "$seed" 2> /dev/null
"$ours" --quiet --solver mst "$work/cloud.xyz" "$work/mst.ply"
"$ours" --quiet "$work/cloud.xyz" "$work/qpbo_i.ply"
"$cgal" --quiet "$work/cloud.xyz" "$work/cgal.xyz"

echo "render_pictures.sh: $large_points points, streamed" >&2
"$make_large_cloud" "$mesh" "$large_points" "$work/large.ply" --seed "$seed" > /dev/null
segments=$("$ours" --quiet --json --stream --write-segments "$work/large.ply" "$work/large_out.ply" |
  sed -n 's/.*"segments": \([0-9]*\),.*/\1/p')

reference=(--color wrong --reference "$mesh")
rows=()
add_row() { # FILE WHAT CLOUD_DESCRIPTION WRONG
  rows+=("| \`$(basename "$1")\` | $2 | $3 | $4 | $(kb "$1") |")
}
f=$(picture "$work/cloud.xyz" "${name}_before")
add_row "$f" "input: PCA normals, random signs (shading)" "$points, noise $noise" "$(wrong "$work/cloud.xyz")"
f=$(picture "$work/qpbo_i.ply" "${name}_after")
add_row "$f" "ours, default solver (shading)" "$points, noise $noise" "$(wrong "$work/qpbo_i.ply")"
f=$(picture "$work/mst.ply" "${name}_wrong_mst" "${reference[@]}")
add_row "$f" "ours, \`--solver mst\` (wrong in red)" "$points, noise $noise" "$(wrong "$work/mst.ply")"
f=$(picture "$work/qpbo_i.ply" "${name}_wrong_qpbo_i" "${reference[@]}")
add_row "$f" "ours, default (MST + QPBO-I) (wrong in red)" "$points, noise $noise" "$(wrong "$work/qpbo_i.ply")"
f=$(picture "$work/cgal.xyz" "${name}_wrong_cgal" "${reference[@]}")
add_row "$f" "\`CGAL::mst_orient_normals\` (wrong in red)" "$points, noise $noise" "$(wrong "$work/cgal.xyz")"
f=$(picture "$work/large_out.ply" "${name}_stream_segments" --color segments)
add_row "$f" "ours, \`--stream\`: its $segments segments" "$large_points (make_large_cloud)" \
  "$(wrong "$work/large_out.ply")"

echo "| picture | what | points | wrong normals | size |"
echo "|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
