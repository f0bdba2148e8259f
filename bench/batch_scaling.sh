#!/usr/bin/env bash
# 1,000 jobs of a 10 s omni scene on ODE through `twinsim batch`: on 1 thread, on 2
# threads, and under `mpirun -np 2` (one thread per rank). Prints jobs per second for
# each (docs/benchmarks.md, docs/scaling.md). Usage: bench/batch_scaling.sh [JOBS]
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${1:-1000}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cat > "$dir/sweep.yaml" <<YAML
name: scaling
seed: 1
command: run
fixed:
  scene: $PWD/scenes/record_plant.yaml
  scene.duration: 10
  backend: ode
random:
  draws: $jobs
  parameters:
    plant.chassis.mass: {uniform: [2.1, 2.5]}
YAML
rate() {  # label, command...
  local label=$1; shift
  local start end
  start=$(date +%s.%N)
  "$@" >/dev/null
  end=$(date +%s.%N)
  awk -v n="$jobs" -v s="$start" -v e="$end" -v l="$label" 'BEGIN { printf "%-22s %7.2f s  %7.2f jobs/s\n", l, e - s, n / (e - s) }'
}
rate "threads, --jobs 1" build/twinsim batch "$dir/sweep.yaml" --out "$dir/t1" --jobs 1 --quiet
rate "threads, --jobs 2" build/twinsim batch "$dir/sweep.yaml" --out "$dir/t2" --jobs 2 --quiet
if command -v mpirun >/dev/null; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  rate "mpirun -np 2, --jobs 1" mpirun -np 2 --oversubscribe build/twinsim batch "$dir/sweep.yaml" --out "$dir/m2" --jobs 1 --quiet
  cmp <(cut -d, -f1-4,6- "$dir/t2/summary.csv") <(cut -d, -f1-4,6- "$dir/m2/summary.csv") && echo "summary.csv: threads and MPI agree"
fi
