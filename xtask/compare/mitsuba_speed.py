#!/usr/bin/env python3
"""Times Mitsuba 3 on scenes/cornell-box: the speed anchor for rrf's path tracer benchmark
(`cargo bench -p rrf-baker --bench path_tracer`), on the same scene with the same settings.

The scene is mitsuba_cornell.py's: the glTF's triangles, Lambert reflectances and emitter,
256x256, 256 spp, box pixel filter, max depth 8, Russian roulette from depth 5, on every core.
The first render of a variant that compiles its kernels (llvm_*) includes that compilation, so
it is reported apart from the runs after it.

    pip install mitsuba numpy
    apt-get install libllvm19        # for the llvm_* variants (LLVM 15 crashes them)
    python3 xtask/compare/mitsuba_speed.py [--variant llvm_ad_rgb] [--runs 3]
"""
import argparse
import tempfile
import time

import drjit as dr
import mitsuba as mi
import numpy as np

from mitsuba_cornell import mitsuba_scene


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default llvm_ad_rgb)")
    parser.add_argument("--runs", type=int, default=3, help="timed renders after the first (default 3)")
    args = parser.parse_args()
    mi.set_variant(args.variant)
    with tempfile.TemporaryDirectory() as tmp:
        description = mitsuba_scene(tmp)
        scene = mi.load_dict(description)
    sensor = description["sensor"]
    paths = sensor["film"]["width"] * sensor["film"]["height"] * sensor["sampler"]["sample_count"]
    for run in range(args.runs + 1):
        start = time.perf_counter()
        image = mi.render(scene, seed=run)
        dr.eval(image)
        dr.sync_thread()
        seconds = time.perf_counter() - start
        mean = np.round(np.array(image).mean(axis=(0, 1)), 4)
        label = "first (with compilation)" if run == 0 else f"run {run}"
        print(f"{args.variant} {label}: {seconds:.2f} s, {paths / seconds / 1e6:.2f} M paths/s (image mean {mean})")


if __name__ == "__main__":
    main()
