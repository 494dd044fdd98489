#!/usr/bin/env python3
"""Candidate seed inputs for the fuzz targets (README.md, "Fuzzing"), written to OUT/<target>/.

    python3 fuzz/make_seeds.py OUT [--photon-maps DIR] [--render-caches DIR]

From tests/data/gltf (the loader's test files), tests/data/gltf-samples (Khronos sample models,
each with its LICENSE.md) and hand-written inputs:
  gltf          every test .gltf/.glb; each Khronos model with its buffers as data: URIs (when
                small enough) or pointing at the fuzzer's buffer.bin, its images at texture.png
                (files fuzz/gltf_fuzzer.cpp puts beside the input), and as a .glb
  scene_bundle  zip, tar and tar.gz bundles of small test scenes (some with sibling files)
  job           valid and invalid job descriptions touching every field (protocol/job.h)
  http_request  raw requests for every route, with the fuzzer's token
  photon_map    with --photon-maps: the .pm files a daemon wrote (photon-maps/ of its cache
                directory), as "checksum appended" inputs (first byte 1) and as they are (0)
  render_cache  with --render-caches: the irradiance-cache files in DIR (any name; those that start
                with the "IRRCACHE" magic), as the photon maps

The committed corpus (fuzz/corpus) is what libFuzzer's -merge=1 kept of these: see README.md.
"""
import argparse
import base64
import io
import json
import pathlib
import struct
import tarfile
import zipfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
MAX_BYTES = 60 * 1024  # under the gltf target's -max_len (Makefile FUZZ_MAX_LEN_gltf)


def write(out: pathlib.Path, name: str, data: bytes) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / name).write_bytes(data)


def glb(document: dict, binary: bytes) -> bytes:
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
    if binary:
        chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def sample_seeds(out: pathlib.Path) -> None:
    for model in sorted((DATA / "gltf-samples").iterdir()):
        for source in sorted(model.glob("glTF/*.gltf")):
            document = json.loads(source.read_text())
            for image in document.get("images", []):
                if "uri" in image:
                    image["uri"] = "texture.png"
            buffers = [(source.parent / b["uri"]).read_bytes() for b in document.get("buffers", [])]
            embedded = json.loads(json.dumps(document))
            for b, data in zip(embedded.get("buffers", []), buffers):
                b["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
            text = json.dumps(embedded, separators=(",", ":")).encode()
            if len(text) <= MAX_BYTES:
                write(out, f"{model.name}.gltf", text)
            else:  # too large: the buffers become the fuzzer's buffer.bin (4 KiB)
                pointed = json.loads(json.dumps(document))
                for b in pointed.get("buffers", []):
                    b["uri"] = "buffer.bin"
                    b["byteLength"] = 4096
                text = json.dumps(pointed, separators=(",", ":")).encode()
                if len(text) <= MAX_BYTES:
                    write(out, f"{model.name}-buffer.bin.gltf", text)
            if len(buffers) == 1 and len(buffers[0]) + 4096 <= MAX_BYTES:
                binary = json.loads(json.dumps(document))
                binary["buffers"][0].pop("uri")
                data = glb(binary, buffers[0])
                if len(data) <= MAX_BYTES:
                    write(out, f"{model.name}.glb", data)


def test_file_seeds(out: pathlib.Path) -> None:
    for source in sorted((DATA / "gltf").rglob("*")):
        if source.suffix in (".gltf", ".glb") and source.stat().st_size <= MAX_BYTES:
            name = str(source.relative_to(DATA / "gltf")).replace("/", "-")
            write(out, name, source.read_bytes())
    # External uris: the fuzzer's files, one below the root, and ways out of it.
    triangle = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2,
                                    "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "texture.png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 72}, {"buffer": 0, "byteOffset": 72, "byteLength": 6}],
        "buffers": [{"uri": "buffer.bin", "byteLength": 4096}],
    }
    for uri in ("buffer.bin", "sub/buffer.bin", "./sub/../buffer.bin", "outside.bin",
                "../buffer.bin", "/etc/hostname", "missing.bin", "buffer%2Ebin"):
        document = json.loads(json.dumps(triangle))
        document["buffers"][0]["uri"] = uri
        write(out, "external-" + uri.replace("/", "_").replace("%", "_") + ".gltf",
              json.dumps(document, indent=1).encode())
    document = json.loads(json.dumps(triangle))
    document["buffers"][0].pop("uri")
    buffer = bytearray(4096)
    struct.pack_into("<18f", buffer, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1)
    struct.pack_into("<4H", buffer, 72, 0, 1, 2, 0)
    write(out, "triangle.glb", glb(document, bytes(buffer[:80])))


def bundle_seeds(out: pathlib.Path) -> None:
    box = DATA / "gltf" / "external" / "Box.gltf"
    files = {
        "plain": {"scene.gltf": (DATA / "gltf" / "indexed_u16.gltf").read_bytes()},
        "textured": {"scene.glb": (DATA / "gltf" / "textured_quad.glb").read_bytes()},
        "external": {"scene.gltf": (DATA / "gltf" / "broken" / "external_buffer.gltf").read_bytes(),
                     "external_buffer.bin": (DATA / "gltf" / "broken" / "external_buffer.bin").read_bytes()},
        "folder": {"model/scene.gltf": (DATA / "gltf" / "fan.gltf").read_bytes(),
                   "model/README.txt": b"a folder of one scene\n"},
        "two-scenes": {"a.gltf": b"{}", "b.gltf": b"{}"},
        "no-scene": {"notes.txt": b"nothing to render\n"},
    }
    if box.exists():
        files["box"] = {"Box.gltf": box.read_bytes()}
    for name, entries in files.items():
        zipped = io.BytesIO()
        with zipfile.ZipFile(zipped, "w", zipfile.ZIP_DEFLATED) as z:
            for path, data in entries.items():
                z.writestr(path, data)
        write(out, f"{name}.zip", zipped.getvalue())
        for mode, suffix in (("w", "tar"), ("w:gz", "tar.gz")):
            tarred = io.BytesIO()
            with tarfile.open(fileobj=tarred, mode=mode, format=tarfile.USTAR_FORMAT) as t:
                for path, data in entries.items():
                    info = tarfile.TarInfo(path)
                    info.size = len(data)
                    info.mtime = 0
                    t.addfile(info, io.BytesIO(data))
            write(out, f"{name}.{suffix}", tarred.getvalue())
    # What the sandbox refuses: a symbolic link, a hard link, "..", an absolute path, a FIFO.
    for kind in ("symlink", "hardlink", "dotdot", "absolute", "fifo"):
        tarred = io.BytesIO()
        with tarfile.open(fileobj=tarred, mode="w", format=tarfile.USTAR_FORMAT) as t:
            scene = (DATA / "gltf" / "strip.gltf").read_bytes()
            info = tarfile.TarInfo("scene.gltf")
            info.size = len(scene)
            t.addfile(info, io.BytesIO(scene))
            info = tarfile.TarInfo({"dotdot": "../evil.bin", "absolute": "/tmp/evil.bin"}.get(kind, "link.bin"))
            if kind == "symlink":
                info.type, info.linkname = tarfile.SYMTYPE, "/etc/hostname"
            elif kind == "hardlink":
                info.type, info.linkname = tarfile.LNKTYPE, "scene.gltf"
            elif kind == "fifo":
                info.type = tarfile.FIFOTYPE
            t.addfile(info, io.BytesIO(b""))
        write(out, f"refused-{kind}.tar", tarred.getvalue())


JOBS = [
    {"scene": {"builtin": "cornell-box"}},
    {"scene": {"builtin": "cornell-box"}, "preset": "preview", "integrator": "photon-map",
     "image": {"width": 64, "height": 48, "tile_size": 16, "spp": 4, "region": [0, 0, 32, 24]},
     "photons": {"global": 1000, "caustic": 500, "k_global": 50, "k_caustic": 20, "seed": 7},
     "gather": {"rays": 16},
     "irradiance_cache": {"enabled": True, "a": 0.2, "gradients": True, "min_spacing_px": 1.5,
                          "max_spacing_px": 20},
     "output": {"pixel_type": "float", "aovs": ["direct", "indirect", "caustic", "albedo", "normal",
                                                 "depth"], "exposure_ev": -1.5},
     "priority": 10, "seed": 18446744073709551615},
    {"scene": {"path": "models/room.gltf"}, "camera": {"gltf_camera": 1}, "integrator": "path"},
    {"scene": {"id": "sha256:" + "0123456789abcdef" * 4},
     "camera": {"look_from": [0, 1, 5], "look_at": [0, 1, 0], "up": [0, 1, 0], "vfov_deg": 45},
     "integrator": "direct", "preset": "reference"},
    {"scene": {"builtin": "sunlit-room"}, "environment": None},
    {"scene": {"builtin": "furnace"}, "environment": {"color": [0.5, 0.6, 0.7], "intensity": 2}},
    {"scene": {"builtin": "spheres-room"},
     "environment": {"image": "sky.exr", "intensity": 1.5, "rotation_deg": -90}},
    {"scene": {"builtin": "caustic"}, "lights": [
        {"type": "point", "position": [0, 2, 0], "intensity": 10, "color": [1, 0.9, 0.8]},
        {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": 5,
         "inner_cone_deg": 10, "outer_cone_deg": 30},
        {"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": 3,
         "angular_diameter_deg": 0.53},
        {"type": "quad", "position": [-0.5, 1.9, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
         "radiance": 8, "two_sided": True}]},
    {"scene": {"builtin": "cornell-box-diffuse"}, "integrator": "path",
     "atmosphere": {"sigma_a": 0.05, "sigma_s": [0.3, 0.4, 0.5], "g": 0.6}},
    {"scene": {"builtin": "sunlit-room"}, "integrator": "direct", "atmosphere": {"sigma_s": 0.2}},
    {"scene": {"path": "models/glass.glb"}, "integrator": "path",
     "material_media": {"Glass.001": {"sigma_s": [0.5, 0.25, 0.125], "g": 0.3},
                        "jade": {"sigma_s": 2, "g": -0.2, "sigma_a": [0.1, 0.01, 0.1]}}},
]
BAD_JOBS = [
    b"", b"{", b"[]", b"null", b'{"scene": {"builtin": "cornell-box"}, "image": {"sppp": 4}}',
    b'{"scene": {"path": "../etc/passwd"}}', b'{"scene": {"builtin": "x", "path": "y"}}',
    b'{"scene": {"builtin": "cornell-box"}, "image": {"width": 16384, "height": 16384}}',
    b'{"scene": {"builtin": "cornell-box"}, "seed": 1e400}',
    b'{"scene": {"builtin": "cornell-box"}, "output": {"aovs": ["depth", "depth"]}}',
    b'{"scene": {"builtin": "cornell-box"}, "camera": {"look_from": [0,0,0], "look_at": [0,0,0]}}',
    b'{"scene": {"builtin": "cornell-box"}, "lights": [{"type": "quad", "edge_u": [1,0,0], "edge_v": [2,0,0]}]}',
    b'{"scene": {"builtin": "cornell-box"}, "irradiance_cache": {"min_spacing_px": 9, "max_spacing_px": 3}}',
    b'{"scene":{"builtin":"cornell-box"},"priority":-1,"image":{"region":[0,0,0,0]}}',
    b'{"a": "\\ud800"}', b"[" * 200,
]


def job_seeds(out: pathlib.Path) -> list:
    texts = []
    for i, job in enumerate(JOBS):
        texts.append(json.dumps(job, indent=1).encode())
        write(out, f"job-{i}.json", texts[-1])
    for i, text in enumerate(BAD_JOBS):
        write(out, f"refused-{i}.json", text)
    return texts


def http_seeds(out: pathlib.Path, jobs: list) -> None:
    auth = b"Authorization: Bearer fuzz-token\r\n"

    def request(method, target, body=b"", headers=b"", token=True):
        head = b"%s %s HTTP/1.1\r\nHost: x\r\n" % (method, target) + (auth if token else b"") + headers
        if body or method in (b"POST", b"PUT"):
            head += b"Content-Length: %d\r\n" % len(body)
        return head + b"\r\n" + body

    job_id = b"20240101-000000-000001-0123456789abcdef"
    key = b"pm1-" + b"0" * 64
    seeds = {
        "healthz": request(b"GET", b"/healthz", token=False),
        "readyz": request(b"GET", b"/readyz", token=False),
        "metrics": request(b"GET", b"/metrics"),
        "openapi": request(b"GET", b"/v1/openapi.json"),
        "no-token": request(b"GET", b"/v1/jobs", token=False),
        "bad-token": request(b"GET", b"/v1/jobs", token=False, headers=b"Authorization: Bearer nope\r\n"),
        "list-jobs": request(b"GET", b"/v1/jobs?state=queued&limit=5"),
        "get-job": request(b"GET", b"/v1/jobs/" + job_id),
        "cancel-job": request(b"DELETE", b"/v1/jobs/" + job_id),
        "events": request(b"GET", b"/v1/jobs/" + job_id + b"/events?last_event_id=3"),
        "tiles": request(b"GET", b"/v1/jobs/" + job_id + b"/tiles"),
        "tile": request(b"GET", b"/v1/jobs/" + job_id + b"/tiles/1/2.exr"),
        "image": request(b"GET", b"/v1/jobs/" + job_id + b"/image.exr?wait=true"),
        "preview": request(b"GET", b"/v1/jobs/" + job_id + b"/preview.png"),
        "list-scenes": request(b"GET", b"/v1/scenes"),
        "get-scene": request(b"GET", b"/v1/scenes/sha256:" + b"ab" * 32),
        "delete-scene": request(b"DELETE", b"/v1/scenes/sha256:" + b"ab" * 32),
        "upload-gltf": request(b"POST", b"/v1/scenes", (DATA / "gltf" / "indexed_u8.gltf").read_bytes()),
        "upload-glb": request(b"POST", b"/v1/scenes", (DATA / "gltf" / "textured_quad.glb").read_bytes()),
        "photon-maps": request(b"GET", b"/v1/photon-maps"),
        "export-photon-map": request(b"GET", b"/v1/photon-maps/" + key),
        "import-photon-map": request(b"PUT", b"/v1/photon-maps/" + key, b"PHOTONMP\x02\0\0\0"),
        "method-not-allowed": request(b"PATCH", b"/v1/jobs", b"{}"),
        "no-route": request(b"GET", b"/nowhere"),
        "malformed": b"GARBAGE\r\n\r\n",
        "keep-alive": request(b"GET", b"/healthz", token=False) + request(b"GET", b"/v1/jobs"),
        "chunked": b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\n" + auth +
                   b"Transfer-Encoding: chunked\r\n\r\n5\r\n{\"sce\r\n0\r\n\r\n",
        "too-large": b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\n" + auth + b"Content-Length: 99999999999\r\n\r\n",
        "expect-continue": request(b"POST", b"/v1/jobs", jobs[0], b"Expect: 100-continue\r\n"),
        "idempotency": request(b"POST", b"/v1/jobs", jobs[0], b"Idempotency-Key: abc-123\r\n"),
        "submit-no-body": request(b"POST", b"/v1/jobs", b""),
    }
    for i, job in enumerate(jobs):
        seeds[f"submit-{i}"] = request(b"POST", b"/v1/jobs", job, b"Content-Type: application/json\r\n")
    for name, data in seeds.items():
        write(out, name + ".http", data)


def photon_map_seeds(out: pathlib.Path, directory: pathlib.Path) -> None:
    for source in sorted(directory.glob("*.pm")):
        data = source.read_bytes()
        if len(data) > 16 * 1024:
            continue
        write(out, source.stem[:16] + "-appended.bin", b"\x01" + data[:-32])
        write(out, source.stem[:16] + "-whole.bin", b"\x00" + data)
    write(out, "empty-appended.bin", b"\x01")
    write(out, "magic-appended.bin", b"\x01PHOTONMP\x02\0\0\0\x04\x03\x02\x01\x18\0\0\0")


def render_cache_seeds(out: pathlib.Path, directory: pathlib.Path) -> None:
    for source in sorted(p for p in directory.iterdir() if p.is_file()):
        data = source.read_bytes()
        if not data.startswith(b"IRRCACHE") or len(data) >= 16 * 1024:  # FUZZ_MAX_LEN_render_cache
            continue
        write(out, source.stem[:24] + "-appended.bin", b"\x01" + data[:-32])
        write(out, source.stem[:24] + "-whole.bin", b"\x00" + data)
    write(out, "empty-appended.bin", b"\x01")
    write(out, "magic-appended.bin", b"\x01IRRCACHE\x01\0\0\0\x04\x03\x02\x01\x70\0\0\0")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=pathlib.Path)
    parser.add_argument("--photon-maps", type=pathlib.Path)
    parser.add_argument("--render-caches", type=pathlib.Path)
    args = parser.parse_args()
    sample_seeds(args.out / "gltf")
    test_file_seeds(args.out / "gltf")
    bundle_seeds(args.out / "scene_bundle")
    jobs = job_seeds(args.out / "job")
    http_seeds(args.out / "http_request", jobs)
    if args.photon_maps:
        photon_map_seeds(args.out / "photon_map", args.photon_maps)
    if args.render_caches:
        render_cache_seeds(args.out / "render_cache", args.render_caches)


if __name__ == "__main__":
    main()
