#!/usr/bin/env bash
# The surface model on a lent GPU machine (docs/training.md, "The surface model"): trained from scratch on every
# train*.npz in DATA (scored on its val.npz) for MIN minutes; the checkpoint and its log land in OUT.
# Here first, the sets (a few minutes each on two cores; training/reproduce.sh, stage 7):
#   python -m training.surface make --split val --cameras continuous paper --out DATA/val.npz
#   python -m training.surface make --split train ... --stretch 0.5 --out DATA/train_s1.npz   (and so on)
# There (device tool, carry DATA): bash training/gpu_surface.sh DATA; then here:
#   python -m training.surface install OUT/last.pt --models ssn_engine/models
# Usage: training/gpu_surface.sh [DATA] (env: MIN, default 8; OUT, default runs/gpu_surface; BATCH; LR)
set -u
DATA=${1:-data/surface_s}
MIN=${MIN:-8}
OUT=${OUT:-runs/gpu_surface}
if [ ! -f "$DATA/val.npz" ] || ! ls "$DATA"/train*.npz > /dev/null 2>&1; then
    echo "no val.npz and train*.npz in $DATA: make them first (python -m training.surface make ...)" >&2
    exit 2
fi
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null
python3 -m training.surface train --data "$DATA" --run "$OUT" --minutes "$MIN" --batch "${BATCH:-128}" \
    --lr "${LR:-2e-3}" --device cuda 2>&1 | tee "$OUT/train.log"
