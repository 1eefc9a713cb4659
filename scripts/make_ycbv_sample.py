#!/usr/bin/env python3
"""Makes datasets/samples/ycbv_real: a few real YCB-Video frames (BOP layout) and their models.

Usage: scripts/make_ycbv_sample.py SOURCE OUT SCENE/IMAGE...
  e.g. scripts/make_ycbv_sample.py PATH/TO/ycbv_real datasets/samples/ycbv_real \
         0/1 0/10 3/138

SOURCE is a BOP folder with split test/ (the ycbv_real conversion). The chosen images keep
their scene and image ids. rgb/, depth/ and mask_visib/ files, camera.json and the licence are
copied byte for byte; scene_camera.json, scene_gt.json and models/models_info.json are
restricted to the chosen images and the objects they show (one entry per line, as in SOURCE);
the models are converted to binary little-endian PLY by ply_ascii_to_binary.py. OUT must not
exist. PROVENANCE.md is written by hand; SHA256SUMS is written here over every other file.
Python 3 stdlib only.
"""
import hashlib
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ply_ascii_to_binary  # noqa: E402


def six(number):
    return f"{number:06d}"


def write_entries(path, entries):
    """`entries` as a JSON object with one key per line, keys in numeric order."""
    keys = sorted(entries, key=int)
    lines = [f"  {json.dumps(key)}: {json.dumps(entries[key])}" for key in keys]
    with open(path, "w", encoding="ascii") as stream:
        stream.write("{\n" + ",\n".join(lines) + "\n}\n")


def read_json(path):
    with open(path, encoding="utf-8") as stream:
        return json.load(stream)


def write_sha256sums(out):
    rows = []
    for folder, _, files in os.walk(out):
        for name in files:
            path = os.path.join(folder, name)
            relative = os.path.relpath(path, out)
            if relative in ("SHA256SUMS", "PROVENANCE.md"):
                continue
            with open(path, "rb") as stream:
                rows.append((relative, hashlib.sha256(stream.read()).hexdigest()))
    with open(os.path.join(out, "SHA256SUMS"), "w", encoding="ascii") as stream:
        for relative, digest in sorted(rows):
            stream.write(f"{digest}  {relative}\n")


def main(source, out, frames):
    if os.path.exists(os.path.join(out, "test")):
        raise SystemExit(f"{out}: already holds test/; remove it first")
    chosen = {}  # scene id -> sorted image ids
    for frame in frames:
        scene, image = (int(part) for part in frame.split("/"))
        chosen.setdefault(scene, set()).add(image)

    object_ids = set()
    for scene, images in sorted(chosen.items()):
        src = os.path.join(source, "test", six(scene))
        dst = os.path.join(out, "test", six(scene))
        camera = read_json(os.path.join(src, "scene_camera.json"))
        gt = read_json(os.path.join(src, "scene_gt.json"))
        keys = [str(image) for image in sorted(images)]
        for key in keys:
            if key not in camera or key not in gt:
                raise SystemExit(f"{src}: image {key} is not in scene_camera.json/scene_gt.json")
        os.makedirs(dst)
        write_entries(os.path.join(dst, "scene_camera.json"), {k: camera[k] for k in keys})
        write_entries(os.path.join(dst, "scene_gt.json"), {k: gt[k] for k in keys})
        for image in sorted(images):
            for folder in ("rgb", "depth"):
                os.makedirs(os.path.join(dst, folder), exist_ok=True)
                name = six(image) + ".png"
                shutil.copyfile(os.path.join(src, folder, name), os.path.join(dst, folder, name))
            os.makedirs(os.path.join(dst, "mask_visib"), exist_ok=True)
            for gt_index, instance in enumerate(gt[str(image)]):
                object_ids.add(instance["obj_id"])
                name = f"{six(image)}_{six(gt_index)}.png"
                shutil.copyfile(os.path.join(src, "mask_visib", name),
                                os.path.join(dst, "mask_visib", name))

    os.makedirs(os.path.join(out, "models"))
    info = read_json(os.path.join(source, "models", "models_info.json"))
    write_entries(os.path.join(out, "models", "models_info.json"),
                  {str(obj): info[str(obj)] for obj in sorted(object_ids)})
    for obj in sorted(object_ids):
        name = f"obj_{six(obj)}.ply"
        ply_ascii_to_binary.convert(os.path.join(source, "models", name),
                                    os.path.join(out, "models", name))
    for name in ("camera.json", "LICENSE_YCB-Video.txt"):
        shutil.copyfile(os.path.join(source, name), os.path.join(out, name))
    write_sha256sums(out)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        raise SystemExit(__doc__.strip().splitlines()[2])
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
