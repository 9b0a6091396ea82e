#!/usr/bin/env bash
# Regenerates the README pictures: records every bundled scene and draws it with `drape render`.
# usage: docs/pictures/make.sh [path/to/drape]   (default: target/release/drape)
set -euo pipefail
cd "$(dirname "$0")/../.."
drape=${1:-target/release/drape}
bags=$(mktemp -d)
trap 'rm -rf "$bags"' EXIT
for scene in config/*.yaml; do
  name=$(basename "$scene" .yaml)
  [ "$name" = node ] && continue
  "$drape" record --quiet --scene "$scene" --out "$bags/$name.mcap" >/dev/null
done
"$drape" render "$bags"/three_corner_{normal,soft_stretch,soft_bending,soft_warp}.mcap \
  --out docs/pictures/three_corner.png --size 180x150 --azimuth -30 --elevation 20 \
  --at 0.3,0.6,1.0,4.0
for b in "$bags"/*.mcap; do
  name=$(basename "$b" .mcap)
  case "$name" in three_corner_*) continue ;; esac
  "$drape" render "$b" --out "docs/pictures/$name.png" --size 240x240 --package-path urdf
done
"$drape" render "$bags/robot_towel.mcap" --out docs/pictures/robot_towel_strip.png --frames 5 \
  --size 200x200 --package-path urdf
