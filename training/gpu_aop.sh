#!/usr/bin/env bash
# AOPs on a lent GPU machine (docs/training.md, "An AOP for a GPU machine"): three runs side by side on one GPU
# from the packed views, each stopped after MIN minutes with its checkpoint copied to $OUT:
#   plain.pt  the plain AOP (blind calls), shipped widths, batch 64
#   flip.pt   the same, mirrored samples and another seed (the shipped AO map is the mean of two such members)
#   camera.pt the AOP given the camera input, half of its samples with the estimator's kind of error
# Every training view stays in memory (--cache-views): the packed file holds them as 8-bit arrays.
# Here first: python -m training.data.packed --data data/ssn256 data/ssn256c --res 128 --out .gpu/aop128.npz
# There (device tool, carry .gpu): bash training/gpu_aop.sh
# Usage: training/gpu_aop.sh [PACKED] (env: MIN, minutes per run, default 7; STEPS, default 40000; OUT)
set -u
PACKED=${1:-.gpu/aop128.npz}
MIN=${MIN:-7}
STEPS=${STEPS:-40000}
OUT=${OUT:-runs/gpu_aop}
RUNS=${RUNS:-/tmp/gpu_aop}
if [ ! -f "$PACKED" ]; then
    echo "no packed views at $PACKED: python -m training.data.packed --data data/ssn256 data/ssn256c --res 128 --out $PACKED" >&2
    exit 2
fi
mkdir -p "$OUT" "$RUNS"
export PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null
COMMON="--module aop --data $PACKED --resolution 128 --batch 64 --steps $STEPS --warmup 200 --threads 4 --cache-views 11000
    --val-every 1000 --log-every 200 --ckpt-minutes 2 --max-minutes $MIN"
run() {
    local name=$1
    shift
    python3 -m training.train $COMMON --run "$RUNS/$name" "$@" > "$RUNS/$name.log" 2>&1
    echo "$name exit $?" >> "$RUNS/$name.log"
}
run plain --seed 1 &
P1=$!
run flip --seed 2 --flip &
P2=$!
run camera --seed 3 --flip --camera --true-camera 0.5 --blind-camera-error 0.176 0.107 &
P3=$!
trap 'kill -TERM $P1 $P2 $P3 2>/dev/null' TERM INT
wait $P1 $P2 $P3
for name in plain flip camera; do
    tail -n 3 "$RUNS/$name.log"
    [ -f "$RUNS/$name/last.pt" ] && cp "$RUNS/$name/last.pt" "$OUT/$name.pt"
done
tar czf "$OUT/logs.tgz" -C "$RUNS" plain.log flip.log camera.log $(cd "$RUNS" && ls -d */log.csv 2>/dev/null)
ls -l "$OUT"
