#!/usr/bin/env bash
# The rain's contact figures over many seeds (docs/design.md, Known limits): the rigid_rain sample with 80 bodies,
# its other settings at their defaults (300 steps of 0.01 s, the corners let go at 1.5 s), for each seed of a
# range, one line per seed and the totals: bodies through the cloth (and of them those that crossed it away from
# its border: SheetCrossings), the deepest cloth vertex in a body and in the floor (mm) with the runs
# beyond 1 mm, and the fastest cloth vertex. The runs are chaotic, so a change is judged over tens of
# seeds, not a few. Needs jq (Debian `jq`) and a build with the samples.
#
#   bash bench/rain_seeds.sh [sample] [first last] [flags...]   # defaults: build/samples/rigid_rain, seeds 1 to 40
#
# Flags after `last` go to the sample, e.g. `--continuous 0` for the scene without continuous contact.
set -euo pipefail
sample=${1:-build/samples/rigid_rain}
first=${2:-1}
last=${3:-40}
shift $(( $# < 3 ? $# : 3 ))
[ -x "$sample" ] || { echo "rain_seeds.sh: $sample not found (build the samples first)" >&2; exit 2; }
command -v jq > /dev/null || { echo "rain_seeds.sh: jq not found (apt-get install jq)" >&2; exit 2; }
json=$(mktemp)
trap 'rm -f "$json"' EXIT

echo "seed  through  interior  body_mm  floor_mm  fastest_m/s"
rows=$(for seed in $(seq "$first" "$last"); do
  "$sample" --bodies 80 --seed "$seed" --json "$@" 2> /dev/null > "$json"
  jq -r --arg seed "$seed" \
    '[$seed, .bodies_through_cloth, .bodies_through_cloth_interior, .max_penetration * 1000,
      .max_floor_penetration * 1000, .max_cloth_speed] | @tsv' \
    "$json"
done)
awk -F '\t' '{ printf "%4d  %7d  %8d  %7.2f  %8.2f  %11.1f\n", $1, $2, $3, $4, $5, $6 }' <<< "$rows"
awk -F '\t' '{ through += $2; interior += $3; if ($4 > body) body = $4; if ($5 > floor) floor = $5;
               if ($6 > fast) fast = $6; deepBody += $4 > 1; deepFloor += $5 > 1 }
             END { printf "seeds %d: %d bodies through (%d away from the border); ", NR, through, interior;
                   printf "deepest in a body %.2f mm (beyond 1 mm in %d runs), ", body, deepBody;
                   printf "in the floor %.2f mm (in %d runs); fastest cloth vertex %.1f m/s\n", floor, deepFloor,
                   fast }' <<< "$rows"
