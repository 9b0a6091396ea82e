#!/usr/bin/env bash
# Regenerates the README pictures: records every bundled scene and draws it with `drape render`
# (defaults: the robot's meshes found as the recording found them, a view that shows the cloth,
# the scene's name and the time on each tile).
# usage: docs/pictures/make.sh [path/to/drape]   (default: target/release/drape)
set -euo pipefail
cd "$(dirname "$0")/../.."
drape=${1:-target/release/drape}
bags=$(mktemp -d)
trap 'rm -rf "$bags"' EXIT
for scene in config/*.yaml; do
  name=$(basename "$scene" .yaml)
  [ "$name" = node ] && continue
  "$drape" record --quiet "$scene" --out "$bags/$name.mcap" >/dev/null
done
# The four materials side by side at four times: one view for all, small tiles.
"$drape" render "$bags"/three_corner_{normal,soft_stretch,soft_bending,soft_warp}.mcap \
  --out docs/pictures/three_corner.png --size 180x150 --azimuth -30 --elevation 20 \
  --at 0.3,0.6,1.0,4.0
for b in "$bags"/*.mcap; do
  name=$(basename "$b" .mcap)
  case "$name" in three_corner_*) continue ;; esac
  "$drape" render "$b" --out "docs/pictures/$name.png"
done
"$drape" render "$bags/robot_towel.mcap" --out docs/pictures/robot_towel_strip.png --frames 5
# The pick by contact alone: closed on the overhang, lifted, carried, let go.
"$drape" render "$bags/robot_pinch_towel.mcap" --out docs/pictures/robot_pinch_towel.png \
  --at 1.3,2.4,3.2,4.5 --size 200x170 --azimuth 50 --elevation 25
# The README's head: the main command's bag animated (every other frame, 15 per second).
"$drape" render "$bags/robot_cape.mcap" --out docs/pictures/robot_cape.gif --frames 61
