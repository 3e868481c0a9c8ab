#!/usr/bin/env bash
# How the shipped Model_BA weights (src/map2map/learn/weights/model_ba.safetensors) are made.
#
# PROVISIONAL weights (this session, no GPU): generated pairs (map2map.learn.synthetic:
# generated plans + the parametric SLAM model), CPU, small network (16 channels).
# FINAL weights (to do): the same two training/export commands on a dataset from
# `map2map dataset build` (>= 4,000 pairs; on a GPU, the thesis's ~534 epochs), default widths.
set -euo pipefail
DS=${DS:-ba_pairs}            # dataset folder (packed.npz inside)
RUN=${RUN:-ba_run}
EPOCHS=${EPOCHS:-10}

if [ ! -f "$DS/packed.npz" ]; then
  # provisional data: 1200 pairs from plans seeded 2000..3199 (held-out benchmarks use 100000..)
  mkdir -p "$DS"
  python3 - "$DS" <<'PY'
import sys
from map2map.datasets.packed import save_packed
from map2map.learn.synthetic import make_pairs
save_packed(f"{sys.argv[1]}/packed.npz", make_pairs(1200, 256, seed=2000))
PY
fi
# the shipped provisional weights: 5 epochs, then extended to 10 with --resume (the learning
# rate decays over the last 30 % of each schedule); with a GPU just give --epochs once
python3 -m map2map train ba --data "$DS" --out "$RUN" --epochs 5 --seed 0 \
  --size 64 --g-channels 16 --g-max-channels 64 --d-channels 16 ${TRAIN_ARGS:-}
python3 -m map2map train ba --data "$DS" --out "$RUN" --resume --epochs "$EPOCHS"
python3 - "$RUN" <<'PY'
import sys
from map2map.learn.autocorrect import export_model
export_model(sys.argv[1], "src/map2map/learn/weights/model_ba.safetensors",
             note="see benchmarks/train_ba.sh")
PY
