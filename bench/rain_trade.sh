#!/usr/bin/env bash
# The accuracy side of the rain's speed/accuracy trade (bench_rigid_rain measures the speed side on the same
# series): the rigid_rain sample, 80 bodies, 200 steps of 0.01 s (the corners let go at 1.5 s), for each series
# of substeps and collision method and each seed; one Markdown row per series with the worst and the median
# over the seeds. Needs jq (Debian `jq`) and a build with the samples.
#
#   bash bench/rain_trade.sh [build-dir] [seeds...]      # defaults: build, seeds 1 2 3 4
set -euo pipefail
build=${1:-build}
shift || true
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4)
sample="$build/samples/rigid_rain"
[ -x "$sample" ] || { echo "rain_trade.sh: $sample not found (build the samples first)" >&2; exit 2; }
command -v jq > /dev/null || { echo "rain_trade.sh: jq not found (apt-get install jq)" >&2; exit 2; }
# Each run's JSON goes to a file and is read after the run: a reader beside a timed run slows it.
json=$(mktemp)
trap 'rm -f "$json"' EXIT

# The median and the largest of the numbers on standard input, one per line.
stats() { sort -g | awk '{ v[NR] = $1 } END { m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2;
                                               printf "%.3g / %.3g", m, v[NR] }'; }

echo "| substeps | contacts | ms per step | bodies through the cloth at the release (of 80) | deepest cloth vertex in a body, mm | largest strain at the end |"
echo "|---|---|---|---|---|---|"
for series in "10 faces" "10 vertices" "5 faces" "2 faces" "1 faces" "2 vertices" "1 vertices"; do
  set -- $series
  out=$(for seed in "${seeds[@]}"; do
    "$sample" --bodies 80 --seed "$seed" --substeps "$1" --method "$2" --steps 200 --json 2> /dev/null > "$json"
    jq -r '[.ms_per_step, .bodies_through_cloth_at_release, .max_penetration * 1000, .final_max_strain] | @tsv' \
      "$json"
  done)
  col() { cut -f "$1" <<< "$out" | stats; }
  contacts=$([ "$2" = vertices ] && echo "vertex only" || echo "vertex and face")
  echo "| $1 | $contacts | $(col 1) | $(col 2) | $(col 3) | $(col 4) |"
done
echo
echo "Each cell: median / worst over seeds ${seeds[*]}."
