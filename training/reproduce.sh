#!/usr/bin/env bash
# The shipped model (ssn_engine/models, v3.11) from the meshes: every stage that made it, in order.
#   1. the datasets: data/ssn128 (the AOP's), data/ssn256 (paper cameras) and data/ssn256c (continuous cameras)
#   2. the AOP: two networks, the shipped AO map is their mean
#   3. the geometry-guided SR: a first run and three fine-tunes, each from the one before
#   4. the AOP given the camera: each AOP network fine-tuned with the camera input
#   5. the camera estimator: its data, then its training
#   6. the export: the graphs, model.json and the model card in OUT, then the estimator installed there
#   7. the surface model (the hard-light tracer's pixel heights): its data, training on a GPU, then installed in OUT
#   8. the surface model fine-tuned on the CPU with new kinds of shapes and the depth, installed with the graph of
#      stage 7 kept as the second reading (each pixel's height the higher of the two)
#   9. the camera estimator fine-tuned on stage 8's sets (their many shapes), chosen on validation views of their
#      kinds, installed in OUT
# On this project's 2-core CPU machine the stages took about: datasets 1 to 2 worker-hours each, AOPs 45 and
# 42 min, SR 59 + 85 + 27 + 42 min, the camera AOPs 28 min side by side, the estimator 35 min (docs/training.md);
# the surface model's data about 3 minutes a set (the later sets 1 minute, or 25 s of people), its training
# 7.3 + 4.1 + 5.6 minutes on one H200 GPU (SURFACE_DEVICE), its fine-tuning 60 minutes on the CPU;
# the estimator's fine-tuning 40 minutes.
# Every training stage resumes from its run's last.pt, so re-running the script continues a stopped stage.
# Install the result with: cp OUT/*.onnx OUT/model.json OUT/MODEL_CARD.md ssn_engine/models/
# Usage: training/reproduce.sh [DATA] [RUNS] [OUT]   (env: DRY_RUN=1 prints the commands without running them)
set -eu
DATA=${1:-data}
RUNS=${2:-runs}
OUT=${3:-$RUNS/m_v311}

run() {
    echo "+ $*"
    if [ -z "${DRY_RUN:-}" ]; then
        "$@"
    fi
}

# surface_sets DIR NAME "SEEDS" OPTIONS...: one surface training set per seed (continuous cameras), written to
# DIR/train_NAME<seed>.npz
surface_sets() {
    local dir=$1 name=$2 seeds=$3
    shift 3
    for seed in $seeds; do
        run python -m training.surface make --split train --cameras continuous --seed "$seed" "$@" \
            --out "$dir/train_$name$seed.npz"
    done
}

# 1. Datasets (docs/dataset.md): the same items and splits at three settings.
ITEMS="--workers 2 --seed 0 --procedural 36 --humans 48"
run python -m training.make_dataset --out "$DATA/ssn128" --res 128 $ITEMS
run python -m training.make_dataset --out "$DATA/ssn256" --res 256 $ITEMS
run python -m training.make_dataset --out "$DATA/ssn256c" --res 256 $ITEMS --cameras continuous

# 2. The AOP (docs/training.md, "AOP ensemble"): the second network mirrored, batch 16, longer.
AOP_COMMON="--module aop --data $DATA/ssn128 --threads 2 --ckpt-minutes 3"
run python -m training.train $AOP_COMMON --run "$RUNS/aop" --steps 3000 --warmup 50 --batch 8 \
    --val-every 100 --log-every 10
run python -m training.train $AOP_COMMON --run "$RUNS/aop_flip" --steps 5000 --warmup 100 --batch 16 --flip \
    --val-every 250 --log-every 20
AOP="$RUNS/aop/last.pt $RUNS/aop_flip/last.pt"

# 3. The geometry-guided SR (docs/training.md, "Geometry-guided SR" and the sections it links): the card as input
# and base, the family mixture of light maps, half of the samples with the AOP's predicted AO (the mean of the two
# networks, as the shipped aop.onnx; the first two runs had the first release's mirror-averaged graph of them).
SR_COMMON="--module sr --card --lights mix --warmup 100 --batch 8 --elms-per-view 4 --threads 2 --cache-views 150
    --swap-every 3 --ao-from $AOP --ao-from-prob 0.5"
run python -m training.train $SR_COMMON --run "$RUNS/sr_card" --data "$DATA/ssn256" --steps 5000 --val-every 250
# (the shipped run stopped at its 85-minute limit, step 4,904 of 5,000)
run python -m training.train $SR_COMMON --run "$RUNS/sr_card2" --data "$DATA/ssn256" --steps 5000 --val-every 250 \
    --init-from "$RUNS/sr_card/last.pt" --lr 5e-4 --flip
run python -m training.train $SR_COMMON --run "$RUNS/sr_cont" --data "$DATA/ssn256c" --steps 3500 --val-every 250 \
    --init-from "$RUNS/sr_card2/last.pt" --lr 3e-4 --flip
run python -m training.train $SR_COMMON --run "$RUNS/sr_zncc2" --data "$DATA/ssn256" "$DATA/ssn256c" --steps 3000 \
    --val-every 500 --init-from "$RUNS/sr_cont/last.pt" --lr 1e-4 --flip --card-blur 1.2 --zncc-weight 0.05

# 4. The AOP given the camera (docs/training.md, "The AOP given the camera"): each AOP network fine-tuned with the
# camera input, half of the samples with the camera moved as the estimator misses it (the shipped two ran side by
# side, one thread each).
k=0
for member in aop aop_flip; do
    run python -m training.train --module aop --camera --run "$RUNS/aop_cam$k" --data "$DATA/ssn256" "$DATA/ssn256c" \
        --steps 3000 --warmup 50 --batch 16 --threads 1 --flip --lr 3e-4 --init-from "$RUNS/$member/last.pt" \
        --val-every 250 --blind-camera-error 0.176 0.107
    k=$((k + 1))
done

# 5. The camera estimator (docs/training.md, "A camera estimator with a distribution").
run python -m training.heights make --split train --cameras continuous paper --out "$DATA/heights128/train.npz"
run python -m training.heights make --split val --cameras continuous paper --out "$DATA/heights128/val.npz"
run python -m training.camera_estimator --data "$DATA/heights128" --out "$RUNS/camera" --minutes 35

# 6. The export. The shipped AOP graph is the first release's mirror-averaged graph of the two networks, rewritten
# to run each network once (export --aop-without-mirror); the SR and the camera AOP are exported from their runs.
run python -m training.export --aop $AOP --sr "$RUNS/sr_zncc2/last.pt" --mirror-average --out "$RUNS/m_aop" \
    --data "$DATA/ssn256c"
run python -m training.export --aop "$RUNS/m_aop/aop.onnx" --aop-without-mirror \
    --aop-camera "$RUNS/aop_cam0/last.pt" "$RUNS/aop_cam1/last.pt" --sr "$RUNS/sr_zncc2/last.pt" --mirror-average \
    --out "$OUT" --data "$DATA/ssn256c" --floor 0.004 --floor-small-lights 0.02 --shadow-reach 16 --ao-gamma 0.6
run python -m training.camera_estimator --out "$RUNS/camera" --minutes 0 --install "$OUT"

# 7. The surface model (docs/hard_light.md, "Where each pixel's surface lies"): pixel heights of three sets of
# training views (other procedural shapes, people and views with each seed), trained on a GPU, then fine-tuned on
# all three sets, then on 30 more sets of views of the meshes and procedural shapes and 20 of people.
SURFACE="$DATA/surface128"
for seed in 0 1 2; do
    name=train$([ "$seed" = 0 ] || echo "_s$seed")
    run python -m training.surface make --split train --cameras continuous paper --seed "$seed" \
        --out "$SURFACE/$name.npz"
done
run python -m training.surface make --split val --cameras continuous paper --out "$SURFACE/val.npz"
run python -m training.surface train --data "$SURFACE" --sets train --run "$RUNS/surface_b" --minutes 7.3 \
    --batch 64 --lr 2e-3 --widths 16 32 64 128 192 256 --device "${SURFACE_DEVICE:-cuda}"
run python -m training.surface train --data "$SURFACE" --sets train train_s1 train_s2 --run "$RUNS/surface_c" \
    --minutes 4.1 --batch 64 --lr 1e-3 --init "$RUNS/surface_b/last.pt" --device "${SURFACE_DEVICE:-cuda}"
surface_sets "$SURFACE" d "$(seq 3 32)" --sources mesh procedural
surface_sets "$SURFACE" h "$(seq 3 22)" --sources anny
run python -m training.surface train --data "$SURFACE" --run "$RUNS/surface_d" --minutes 5.6 --batch 128 \
    --lr 1e-3 --init "$RUNS/surface_c/last.pt" --device "${SURFACE_DEVICE:-cuda}"
run python -m training.surface install "$RUNS/surface_d/last.pt" --models "$OUT"

# 8. The surface model fine-tuned (docs/training.md, "The surface model"): on the CPU, from stage 7's graph, on
# sets of the meshes and procedural shapes, people standing and off their feet, procedural animals and objects
# with parts on the ground, reading the depth too; installed with stage 7's graph kept as the second reading.
FT="$DATA/surface_ft"
run python -m training.surface make --split train --cameras continuous paper --out "$FT/train.npz"
run python -m training.surface make --split val --cameras continuous paper --out "$FT/val.npz"
surface_sets "$FT" p "$(seq 9 14)" --sources mesh procedural
surface_sets "$FT" h "$(seq 13 24)" --sources anny --stretch 0.25
surface_sets "$FT" q "$(seq 41 46)" --sources quadruped --quadrupeds 200
surface_sets "$FT" a "$(seq 61 66)" --sources anny_poses
surface_sets "$FT" g "$(seq 81 86)" --sources grounded --grounded 200
run python -m training.surface train --data "$FT" --run "$RUNS/surface_e" --minutes 60 --batch 32 --lr 3e-4 \
    --device cpu --init "$RUNS/surface_d/last.pt" --depth --depth-weight 4
run python -m training.surface install "$RUNS/surface_e/last.pt" --models "$OUT" --second "$OUT/surface.onnx"

# 9. The camera estimator fine-tuned (docs/training.md, "Stage 5"): from the graph installed in stage 6, on stage
# 8's sets (the meshes and procedural shapes, people standing and in poses, procedural animals, objects with parts
# on the ground), the step chosen on validation views of the same kinds.
Q="$DATA/surface_q"
run python -m training.surface make --split val --cameras continuous paper --sources quadruped --quadrupeds 200 \
    --out "$Q/val_q.npz"
run python -m training.surface make --split val --cameras continuous paper --sources anny_poses --out "$Q/val_a.npz"
run python -m training.surface make --split val --cameras continuous paper --sources grounded --grounded 200 \
    --out "$Q/val_g.npz"
run python -m training.camera_estimator --data "$FT" "$Q" --out "$RUNS/camera_ft" --minutes 40 --lr 5e-4 \
    --init-from "$OUT/camera.onnx" --install "$OUT"
