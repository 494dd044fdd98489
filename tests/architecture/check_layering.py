#!/usr/bin/env python3
"""Checks that the source tree is layered one way (docs/ARCHITECTURE.md, "Layers").

Every folder below is a layer; a file may include headers of its own folder and of folders on a
lower layer only. Folders on the same layer do not include each other, so each can be read, tested
and changed without the others. Exit status 1 lists every include that runs the wrong way.
"""
import re
import sys
from pathlib import Path

# Lowest first. A folder not listed here is an error, so a new folder has to be given its place.
LAYERS = [
    ["core/util"],
    ["core/math"],
    ["core/medium"],                                        # participating media: coefficients, sampling
    ["core/scene"],                                         # the scene as data, and loading it
    ["core/accel", "core/camera", "core/image", "core/material"],
    ["core/light"],
    ["core/shading"],                                       # the scene as light transport sees it
    ["core/photon"],
    ["core/integrators"],
    ["core/render"],
    ["core/tools", "protocol"],
    ["server", "clients"],
]

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)
SOURCE_SUFFIXES = {".h", ".hpp", ".cpp", ".cc"}


def layer_of(folder_to_layer, path):
    """The (folder, layer) a repository-relative path belongs to, or None outside every layer."""
    for folder, layer in folder_to_layer.items():
        if path == folder or path.startswith(folder + "/"):
            return folder, layer
    return None


def violations(root):
    folder_to_layer = {folder: i for i, layer in enumerate(LAYERS) for folder in layer}
    found = []
    for top in ("core", "protocol", "server", "clients"):
        for path in sorted((root / top).rglob("*")):
            if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
                continue
            relative = path.relative_to(root).as_posix()
            own = layer_of(folder_to_layer, relative)
            if own is None:
                found.append(f"{relative}: its folder has no layer in {Path(__file__).name}")
                continue
            for included in INCLUDE.findall(path.read_text(encoding="utf-8")):
                target = layer_of(folder_to_layer, included)
                if target is None:
                    continue  # a header beside it or a generated one, not a layer of ours
                if target[0] == own[0]:
                    continue
                if target[1] >= own[1]:
                    how = "the same layer" if target[1] == own[1] else "a higher layer"
                    found.append(f"{relative} includes {included}: {target[0]} is on {how} than {own[0]}")
    return found


def main():
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2]
    found = violations(root)
    for line in found:
        print(line)
    if found:
        print(f"{len(found)} include(s) run against the layers")
        return 1
    print("every include runs down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main())
