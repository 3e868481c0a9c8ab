#!/usr/bin/env bash
# How the shipped Model_BA weights (src/map2map/learn/ba/weights/model_ba.safetensors) are made.
#
# Current weights (2026-11-26): trained on one NVIDIA H200 by benchmarks/gpu_session.py, i.e.
#   DS=gen6400 EPOCHS=111 TRAIN_ARGS="--batch 256 --save-every 5"  (default widths, 64 px)
# on `dataset build --count 6400 --seed 0` (4,209 complete pairs, 3,358 train), 168 s at
# 2,403 img/s. Previous weights (CPU, 16 epochs, --g-channels 16 --g-max-channels 64
# --d-channels 16 on gen6300) are in git history. Figures: docs/autocorrect.md, "Trained on a GPU".
set -euo pipefail
DS=${DS:-gen6400}             # a `map2map dataset build` folder
RUN=${RUN:-ba_run}
EPOCHS=${EPOCHS:-111}
WORKERS=${WORKERS:-2}

if [ ! -f "$DS/packed.npz" ]; then   # `dataset export --format packed` writes it
  # the thesis-scale build: 6,400 generated plans, seed 0 (about 1.7 h on a 2-core machine;
  # resumable: run the script again after an interruption)
  python3 -m map2map dataset build --out "$DS" --plans generated --count 6400 --seed 0 \
    --workers "$WORKERS"
  python3 -m map2map dataset clean "$DS"
  python3 -m map2map dataset export "$DS" --format packed
fi
if [ ! -f "$RUN/last.safetensors" ]; then
  python3 -m map2map train ba --data "$DS" --out "$RUN" --epochs "$EPOCHS" --seed 0 \
    --size 64 ${TRAIN_ARGS:---batch 256 --save-every 5}
fi
python3 -m map2map train ba --data "$DS" --out "$RUN" --resume --epochs "$EPOCHS"
python3 - "$RUN" <<'PY'
import sys
from map2map.learn.autocorrect import export_model
export_model(sys.argv[1], "src/map2map/learn/ba/weights/model_ba.safetensors",
             note="see benchmarks/train_ba.sh and docs/autocorrect.md")
PY
