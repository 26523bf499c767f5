#!/usr/bin/env python3
"""Renders scenes/cornell-box with Mitsuba 3 and compares it with `rrf reference`.

An independent check of rrf's path tracer; rrf does not depend on it.

    pip install mitsuba numpy
    cargo run --release -- reference scenes/cornell-box --spp 256 --seed 1 -o out/rrf-a.exr
    cargo run --release -- reference scenes/cornell-box --spp 256 --seed 2 -o out/rrf-b.exr
    python3 xtask/compare/mitsuba_cornell.py out/rrf-a.exr out/rrf-b.exr

Both renderers: 256x256, 256 spp, box pixel filter, max depth 8, Russian roulette from
depth 5. Mitsuba gets the same triangles, Lambert reflectances and emitter, read from the
glTF. Prints the image means, and the difference in 8x8-pixel blocks against the noise that
rrf's two independent seeds show between themselves.
"""
import json
import struct
import sys
import tempfile
from pathlib import Path

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "cornell-box"


def accessor(gltf, binary, index):
    a = gltf["accessors"][index]
    view = gltf["bufferViews"][a["bufferView"]]
    count = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[a["type"]]
    dtype = {5126: np.float32, 5125: np.uint32}[a["componentType"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    data = np.frombuffer(binary, dtype=dtype, count=a["count"] * count, offset=start)
    return data.reshape(a["count"], count) if count > 1 else data


def write_ply(path, positions, faces):
    with open(path, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\n")
        f.write(f"element vertex {len(positions)}\nproperty float x\nproperty float y\nproperty float z\n".encode())
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        f.write(positions.astype("<f4").tobytes())
        for tri in faces:
            f.write(struct.pack("<Biii", 3, *map(int, tri)))


def mitsuba_scene(tmp):
    gltf = json.loads((SCENE / "scene.gltf").read_text())
    binary = (SCENE / "scene.bin").read_bytes()
    shapes = {}
    for node in gltf["nodes"]:
        if "mesh" not in node:
            continue
        prim = gltf["meshes"][node["mesh"]]["primitives"][0]
        positions = accessor(gltf, binary, prim["attributes"]["POSITION"]) + np.array(node.get("translation", [0, 0, 0]))
        faces = accessor(gltf, binary, prim["indices"]).reshape(-1, 3)
        path = Path(tmp) / f"{node['name']}.ply"
        write_ply(path, positions, faces)
        material = gltf["materials"][prim["material"]]
        shape = {"type": "ply", "filename": str(path), "face_normals": True}
        emission = material.get("emissiveFactor")
        if emission:
            strength = material.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
            shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [c * strength for c in emission]}}
        else:
            rgb = material["pbrMetallicRoughness"]["baseColorFactor"][:3]
            shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}
        shapes[node["name"]] = shape
    camera = next(n for n in gltf["nodes"] if "camera" in n)
    fov = np.degrees(gltf["cameras"][camera["camera"]]["perspective"]["yfov"])
    eye = camera["translation"]
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8, "rr_depth": 5},
        "sensor": {
            "type": "perspective",
            "fov": float(fov),
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=[eye[0], eye[1], 0.0], up=[0, 1, 0]),
            "sampler": {"type": "independent", "sample_count": 256},
            "film": {"type": "hdrfilm", "width": 256, "height": 256, "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        },
        **shapes,
    }


def blocks(image, size=8):
    h, w, c = image.shape
    return image.reshape(h // size, size, w // size, size, c).mean(axis=(1, 3))


def main():
    ours = [np.array(mi.Bitmap(p).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)) for p in sys.argv[1:3]]
    with tempfile.TemporaryDirectory() as tmp:
        reference = np.array(mi.render(mi.load_dict(mitsuba_scene(tmp)), spp=256))
    mi.Bitmap(reference).write(str(ROOT / "out" / "mitsuba.exr"))
    mean_ours = (ours[0].mean(axis=(0, 1)) + ours[1].mean(axis=(0, 1))) / 2
    mean_mitsuba = reference.mean(axis=(0, 1))
    print("image mean  rrf     ", np.round(mean_ours, 5))
    print("image mean  Mitsuba ", np.round(mean_mitsuba, 5))
    print("relative difference ", np.round(mean_ours / mean_mitsuba - 1, 4))
    # Structured differences: 8x8 blocks of rrf minus Mitsuba, against the noise between
    # two rrf seeds (whose difference has twice the variance of one image's noise).
    noise = (blocks(ours[0]) - blocks(ours[1])).std() / np.sqrt(2)
    difference = blocks((ours[0] + ours[1]) / 2) - blocks(reference)
    print("block noise (rrf)   ", round(float(noise), 5))
    print("block difference rms", round(float(np.sqrt((difference ** 2).mean())), 5),
          "(noise of the two-seed mean and Mitsuba together:", round(float(noise * np.sqrt(1 / 2 + 1)), 5), ")")
    worst = np.unravel_index(np.abs(difference).argmax(), difference.shape)
    print("largest block difference", round(float(difference[worst]), 5), "at block", worst[:2])


if __name__ == "__main__":
    main()
