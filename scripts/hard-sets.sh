#!/usr/bin/env bash
# The hard synthetic sets of docs/hard-sets.md (issue 17, item 1): makes them with
# pickdetect-synth and measures every method on each with pickdetect-eval at its defaults (all
# models loaded). Writes OUT/SET/ (the dataset) and OUT/results/SET.{txt,json,jsonl}, then
# prints the tables of docs/hard-sets.md (scripts/hard-sets-errors.py). Run from the worktree's
# root after scripts/build.sh; OUT defaults to build/hard-sets (never commit the sets).
#
#   bash scripts/hard-sets.sh                # make the sets and measure them
#   MAKE=0 bash scripts/hard-sets.sh         # measure the sets already made (the "after")
#   SEED=23 OUT=build/hard-sets-23 bash scripts/hard-sets.sh   # the same sets from another seed
set -euo pipefail
cd "$(dirname "$0")/.."
S=${SYNTH:-build/tools/synth/pickdetect-synth}
E=${EVAL:-build/tools/eval/pickdetect-eval}
D=/usr/share/doc/opencv-doc/examples/data
O=${OUT:-build/hard-sets}
C="-n 12 --size 640x480 --seed ${SEED:-17}"
if [ "${MAKE:-1}" != 0 ]; then
  # The reference: the heaps and belts of soft-model and glare without either option.
  $S $C --instances 4-8 --scale 0.45-0.55 -o $O/plain $D/box.png
  $S $C --packed 2 --scale 0.42-0.5 -o $O/packed $D/box.png
  $S $C --aspect 4 --instances 4-8 --scale 0.5-0.65 -o $O/elongated $D/box.png
  $S $C --bundle 4 --instances 2-4 --scale 0.3-0.38 -o $O/bundle $D/box.png
  $S $C --camera 38 --tilt 0 --instances 4-8 --scale 0.45-0.55 -o $O/perspective $D/box.png
  $S $C --soft-models --instances 4-8 --scale 0.45-0.55 -o $O/soft-model $D/box.png
  $S $C --family 0.4 --faces 3 --instances 4-8 --scale 0.45-0.55 -o $O/faces \
    $D/box.png $D/fruits.jpg $D/home.jpg $D/starry_night.jpg
  $S $C --glare 6 --instances 4-8 --scale 0.45-0.55 -o $O/glare $D/box.png
  $S $C --packed 2 --camera 40 --soft-models --glare 6 --scale 0.55-0.62 -o $O/tote-like \
    $D/box.png
  $S $C --packed 2 --camera 40 --soft-models --glare 6 --scale 0.5-0.55 --aspect 2.5 \
    --family 0.4 --faces 3 -o $O/tote-like-faces $D/box.png $D/fruits.jpg $D/home.jpg \
    $D/starry_night.jpg
  # A depalletizing cell's front (1280x720): rows of bundles of seven identical packs, three
  # products, labels and other objects lying on them, glare.
  $S -n 12 --size 1280x720 --seed ${SEED:-17} --bundle 7 --packed 2 --covers 3 --glare 6 \
    --scale 0.3-0.36 --mixed-products -o $O/pallet $D/box.png $D/HappyFish.jpg $D/blox.jpg
fi
sets="plain packed elongated bundle perspective soft-model faces glare tote-like tote-like-faces
  pallet"
mkdir -p $O/results
for s in $sets; do
  $E -o $O/results/$s.jsonl $O/$s >$O/results/$s.txt 2>/dev/null
  $E --json --score $O/results/$s.jsonl $O/$s >$O/results/$s.json 2>/dev/null
done
python3 scripts/hard-sets-errors.py $O $sets
