#!/bin/sh
# Vendor three.js (pinned) into axialdeform/web/vendor/ from its npm package.
# The page and the notebook widget load these files; nothing is fetched at run time.
# Usage: tools/vendor_three.sh   (needs npm; re-run after changing THREE_VERSION)
set -eu
THREE_VERSION=0.160.1
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DEST="$ROOT/axialdeform/web/vendor"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
(cd "$WORK" && npm pack --silent "three@$THREE_VERSION" >/dev/null && tar xzf "three-$THREE_VERSION.tgz")
P="$WORK/package"
rm -rf "$DEST"
mkdir -p "$DEST/addons/controls" "$DEST/addons/loaders" "$DEST/addons/utils"
cp "$P/build/three.module.min.js" "$DEST/"
cp "$P/examples/jsm/controls/OrbitControls.js" "$DEST/addons/controls/"
cp "$P/examples/jsm/loaders/GLTFLoader.js" "$DEST/addons/loaders/"
cp "$P/examples/jsm/utils/BufferGeometryUtils.js" "$DEST/addons/utils/"
cp "$P/LICENSE" "$DEST/LICENSE"
echo "$THREE_VERSION" > "$DEST/VERSION"
echo "vendored three@$THREE_VERSION into $DEST"
