#!/bin/sh
# Rebuilds three.bundle.min.js, the part of three.js the animation page of
# `eom-gen animate` inlines (OrbitControls included), from the npm
# registry. Run by hand when upgrading three; the build never runs it
# (the bundle is committed, so no build step needs the network).
#   three 0.187.0, esbuild 0.28.2 (MIT licences: THREE-LICENSE)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund three@0.187.0 esbuild@0.28.2 >/dev/null
cp "$here/three-entry.js" entry.js
npx esbuild entry.js --bundle --minify --format=iife --global-name=THREE \
  --legal-comments=none --outfile="$here/three.bundle.min.js"
cp node_modules/three/LICENSE "$here/THREE-LICENSE"
rm -rf "$work"
ls -l "$here/three.bundle.min.js"
