#!/usr/bin/env bash
# The first release's CPU training and the paper's ablation (docs/training.md, "The CPU run here"): two AOPs (the
# shipped AO map is still their mean), then SSN (shadow target) and Non-inv-SSN (irradiance target) side by side with
# one thread each (same budget, a fair ablation). The shipped model's whole recipe is training/reproduce.sh.
# Every stage resumes from its run's last.pt, so re-running this script continues where a stopped run left off.
# Usage: training/pipeline.sh [DATA] [RUNS]
#   (env: AOP_STEPS, AOP2_STEPS, SR_STEPS, AOP_MIN, SR_MIN (0: no limit), BATCH)
set -u
DATA=${1:-data/ssn128}
RUNS=${2:-runs}
AOP_STEPS=${AOP_STEPS:-3000}
AOP2_STEPS=${AOP2_STEPS:-5000}
SR_STEPS=${SR_STEPS:-5500}
AOP_MIN=${AOP_MIN:-0}
SR_MIN=${SR_MIN:-0}
BATCH=${BATCH:-8}
COMMON="--data $DATA --batch $BATCH --ckpt-minutes 3 --val-every 100 --log-every 10"
python -m training.train --module aop --run "$RUNS/aop" --steps "$AOP_STEPS" --warmup 50 --threads 2 \
    --max-minutes "$AOP_MIN" $COMMON
# The second AOP: mirrored samples, batch 16, longer. It fits objects better and people worse than the first.
python -m training.train --module aop --run "$RUNS/aop_flip" --steps "$AOP2_STEPS" --warmup 100 --threads 2 --flip \
    --max-minutes "$AOP_MIN" $COMMON --batch 16 --val-every 250 --log-every 20
SR_AO="--ao-from $RUNS/aop/last.pt --ao-from-prob 0.5"  # half the SR samples see the AOP's predicted AO
python -m training.train --module sr --target shadow --run "$RUNS/sr" --steps "$SR_STEPS" --warmup 50 --threads 1 \
    --max-minutes "$SR_MIN" $SR_AO $COMMON &
SR=$!
python -m training.train --module sr --target irradiance --run "$RUNS/sr_noninv" --steps "$SR_STEPS" --warmup 50 \
    --threads 1 --max-minutes "$SR_MIN" $SR_AO $COMMON &
NONINV=$!
trap 'kill -TERM $SR $NONINV 2>/dev/null' TERM INT
wait $SR $NONINV
