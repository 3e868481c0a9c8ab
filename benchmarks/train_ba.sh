#!/usr/bin/env bash
# How the shipped Model_BA weights (src/map2map/learn/weights/model_ba.safetensors) are made.
#
# Current weights (2026-11-24, no GPU lent: CPU, 16 epochs at 64 px, small widths) were made
# by exactly these commands with EPOCHS=16, the first training call stopped by Ctrl-C in
# epoch 5 and continued by the --resume call (the learning-rate schedule is a pure function
# of the epoch, so stopping and resuming does not change the result). On a GPU use the
# default widths and the thesis's epochs (e.g. EPOCHS=534 TRAIN_ARGS="--size 256").
# Figures: docs/learn.md, "Retrained at thesis scale".
set -euo pipefail
DS=${DS:-gen6300}             # a `map2map dataset build` folder
RUN=${RUN:-ba_run}
EPOCHS=${EPOCHS:-16}
WORKERS=${WORKERS:-2}

if [ ! -f "$DS/packed.npz" ]; then   # `dataset export --format packed` writes it
  # the thesis-scale build: 6,300 generated plans, seed 0 (about 3.5 h on a 2-core machine;
  # resumable: run the script again after an interruption)
  python3 -m map2map dataset build --out "$DS" --plans generated --count 6300 --seed 0 \
    --workers "$WORKERS"
  python3 -m map2map dataset clean "$DS"
  python3 -m map2map dataset export "$DS" --format packed
fi
if [ ! -f "$RUN/last.safetensors" ]; then
  python3 -m map2map train ba --data "$DS" --out "$RUN" --epochs "$EPOCHS" --seed 0 \
    --size 64 --g-channels 16 --g-max-channels 64 --d-channels 16 ${TRAIN_ARGS:-}
fi
python3 -m map2map train ba --data "$DS" --out "$RUN" --resume --epochs "$EPOCHS"
python3 - "$RUN" <<'PY'
import sys
from map2map.learn.autocorrect import export_model
export_model(sys.argv[1], "src/map2map/learn/weights/model_ba.safetensors",
             note="see benchmarks/train_ba.sh and docs/learn.md")
PY
