#!/usr/bin/env bash
# On the GPU host, installs what scripts/gpu_carry.sh brought: the carried wheels not installed yet
# (in one pip call: mujoco and mujoco-core share a package folder and must go in together) into
# R/site, a dist-info that names the `jax3dc` subcommands (they are entry points, and the project is
# not installed there), and GLVND's libEGL unpacked into R/gl (the image has none).
# Usage: bash scripts/gpu_host_setup.sh R   (then PYTHONPATH=R/site, LD_LIBRARY_PATH=R/gl/usr/lib/x86_64-linux-gnu)
set -uo pipefail
R=$1
mkdir -p "$R/site"
new=(); for w in .whl/*.whl; do [ -f "$w" ] || continue; grep -qxF "${w##*/}" "$R/site/.wheels" 2>/dev/null || new+=("$w"); done
if [ ${#new[@]} -gt 0 ]; then
  pip install -q --no-deps --target "$R/site" "${new[@]}" 2>&1 | grep -v "as the 'root' user"
  [ "${PIPESTATUS[0]}" -eq 0 ] && printf '%s\n' "${new[@]##*/}" >> "$R/site/.wheels"
fi
mkdir -p "$R/site/jax3dc-0.dist-info" && printf 'Metadata-Version: 2.1\nName: jax3dc\nVersion: 0\n' > "$R/site/jax3dc-0.dist-info/METADATA"
sed -n '/^\[project.entry-points."jax3dc.commands"\]/,/^$/p' pyproject.toml | sed 's/^\[project.entry-points."\(.*\)"\]/[\1]/; s/"//g' \
    > "$R/site/jax3dc-0.dist-info/entry_points.txt"
[ -d "$R/gl" ] || for d in .gl/*.deb; do [ -f "$d" ] && dpkg -x "$d" "$R/gl"; done
