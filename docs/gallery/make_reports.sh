#!/usr/bin/env bash
# Writes the HTML report (docs/report.md) of every example with something to draw, and a
# screenshot of each taken by headless Chromium, into OUT (default build/gallery-reports):
#     docs/gallery/make_reports.sh [NHDYN] [OUT]
# The reports are 1.5-3 MB each (the embedded JavaScript libraries), so the repository keeps only
# the screenshots (made smaller by shrink_png.py), in docs/gallery/reports/ (cp OUT/*.png
# docs/gallery/reports/), shown in the table of docs/gallery/README.md with the command that
# writes each report.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
nhdyn=${1:-$root/build/apps/nhdyn/nhdyn}
out=${2:-$root/build/gallery-reports}
mkdir -p "$out"
# name, end time, time of the screenshot, further options of simulate; the model is
# examples/NAME.toml, or docs/gallery/NAME.toml for the gallery's own (the torus wheel)
runs=(
  "sled 6 4" "sled_paper 6 4" "chaplygin_sleigh 10 6" "knife_edge 4 3" "appell 2 1.5"
  "double_pendulum 5 3" "pendulum_cartesian 4 1" "rolling_disk_bodies 6 2" "whipple_bicycle 10 4"
  "rattleback 6 2.5" "chaplygin_ball 5 3" "ball_in_bowl 3 1.2 --set x0=0.03" "ball_over_bump 2 0.3"
  "tippe_top 3 2" "torus_wheel 6 1" "ball_on_incline 1.2 0.9" "ball_on_turntable 6 2.5"
  "egg 4 1.5" "ball_in_paraboloid 6 3"
)
for run in "${runs[@]}"; do
  read -r name t_end shot options <<<"$run"
  model="$root/examples/$name.toml"
  [[ -f "$model" ]] || model="$here/$name.toml"
  # shellcheck disable=SC2086 # the options are words
  "$nhdyn" simulate "$model" --t-end "$t_end" $options -q -o "$out/$name.csv" --html "$out/$name.html"
  if command -v chromium >/dev/null; then
    profile=$(mktemp -d)
    chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
      --disable-component-update --disable-sync --hide-scrollbars --user-data-dir="$profile" \
      --window-size=1300,760 --virtual-time-budget=5000 --screenshot="$out/$name.png" \
      "file://$out/$name.html#paused&t=$shot" >/dev/null 2>&1 || echo "no screenshot of $name" >&2
    rm -rf "$profile"
    [[ -f "$out/$name.png" ]] && "$(command -v /usr/bin/python3 || command -v python3)" "$here/shrink_png.py" "$out/$name.png"
  fi
  echo "$name: $(du -h "$out/$name.html" | cut -f1) -> $out/$name.html"
done
