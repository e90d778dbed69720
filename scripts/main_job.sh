#!/usr/bin/env bash
# The README's main job: the plain forward trace of the built-in atrium at 1920x1080 with 256
# lights, replayed on the default GPU (the Series6XT-class preset); results in out/run.db, images
# and heat maps in out/images/.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p out
build/tbdrsim trace --technique plain_forward --scene atrium:3 --lights 256 --camera entrance \
  --resolution 1920x1080 --out out/plain_forward.trace
build/tbdrsim run --config configs/series6xt_gx6450.ini --trace out/plain_forward.trace --db out/run.db \
  --images out/images
echo "results: out/run.db (sqlite3 out/run.db 'SELECT * FROM runs'), images: out/images/"
