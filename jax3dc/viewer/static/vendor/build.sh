#!/usr/bin/env bash
# Rebuilds three.bundle.min.js from the pinned npm packages (needs node and npm; run by hand when
# upgrading three.js, then commit the bundle, its licence and VENDORED.json).
set -euo pipefail
THREE=0.187.0
ESBUILD=0.28.2
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --save-exact "three@$THREE" "esbuild@$ESBUILD" >/dev/null
cp "$here/entry.mjs" .
npx esbuild entry.mjs --bundle --format=iife --global-name=THREE --minify --legal-comments=eof \
  --outfile="$here/three.bundle.min.js"
cp node_modules/three/LICENSE "$here/LICENSE-three.txt"
cp node_modules/esbuild/LICENSE.md "$here/LICENSE-esbuild.txt"  # its module glue is in the bundle
python3 - "$here" "$THREE" "$ESBUILD" <<'PY'
import hashlib, json, sys
from pathlib import Path
here, three, esbuild = Path(sys.argv[1]), sys.argv[2], sys.argv[3]
bundle = (here / "three.bundle.min.js").read_bytes()
doc = {"three.bundle.min.js": {"npm": {"three": three, "esbuild": esbuild},
                              "contents": ["three", "three/examples/jsm/loaders/GLTFLoader.js",
                                           "three/examples/jsm/controls/OrbitControls.js"],
                              "licences": ["LICENSE-three.txt", "LICENSE-esbuild.txt"],
                              "sha256": hashlib.sha256(bundle).hexdigest()}}
(here / "VENDORED.json").write_text(json.dumps(doc, indent=1) + "\n")
PY
echo "wrote $here/three.bundle.min.js"
