#!/usr/bin/env python3
"""The standard-library Python client (clients/python/photond_client, imported from the source
tree) against a real daemon on a free loopback port. Run by ctest as `python_client`, with
PHOTOND_BINARY_DIR set to the build directory (or pass it as the first argument). The installed
package and its photond-submit command: test_python_package.py."""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(SOURCE_DIR, "clients", "python"))

from photond_client import PhotondClient, PhotondError  # noqa: E402

BINARY_DIR = os.environ.get("PHOTOND_BINARY_DIR", os.path.join(SOURCE_DIR, "build"))
PHOTOND = os.path.join(BINARY_DIR, "server", "photond")
TEST_DATA = os.path.join(SOURCE_DIR, "tests", "data")
EXR_MAGIC = b"\x76\x2f\x31\x01"

SMALL_JOB = {
    "scene": {"builtin": "cornell-box"},
    "preset": "preview",
    "image": {"width": 64, "height": 48, "spp": 1, "tile_size": 16},
    "photons": {"global": 4000, "caustic": 2000},
    "gather": {"rays": 16},
}


def small_job(**camera):
    job = json.loads(json.dumps(SMALL_JOB))
    if camera:
        job["camera"] = dict(camera)
    return job


class Daemon:
    """`photond serve --listen 127.0.0.1:0` with a temporary cache directory (and `extra_args`)."""

    def __init__(self, directory, extra_args=()):
        self.log_path = os.path.join(directory, "daemon.log")
        self.log = open(self.log_path, "wb")
        # stdout goes to the log too (a pipe nobody reads would block the daemon when full).
        self.process = subprocess.Popen(
            [PHOTOND, "serve", "--listen", "127.0.0.1:0", "--cache-dir",
             os.path.join(directory, "cache"), "--threads", "2", *extra_args],
            stdout=self.log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.url = None
        deadline = time.monotonic() + 30
        while self.url is None and time.monotonic() < deadline:
            for line in self.log_text().splitlines():
                if line.startswith("listening on "):
                    self.url = line[len("listening on "):].strip()
                    break
            if self.url is None:
                if self.process.poll() is not None:
                    break
                time.sleep(0.02)
        if self.url is None:
            self.stop()
            raise RuntimeError(f"{PHOTOND} serve did not print 'listening on URL':\n"
                               f"{self.log_text()}")

    def log_text(self):
        with open(self.log_path, "rb") as log:
            return log.read().decode("utf-8", "replace")

    def stop(self):
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.log.close()


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = tempfile.mkdtemp(prefix="photond_python_client_")
        try:
            cls.daemon = Daemon(cls.directory)
        except BaseException:
            shutil.rmtree(cls.directory, ignore_errors=True)  # tearDownClass will not run
            raise
        cls.client = PhotondClient(cls.daemon.url)

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        shutil.rmtree(cls.directory, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.directory, name)

    def test_submit_events_tiles_and_image(self):
        job_id = self.client.submit(small_job())
        seen = []
        status = self.client.wait(job_id, timeout=60, on_event=seen.append)
        self.assertEqual(status["state"], "done", status)
        self.assertEqual(status["progress"]["tiles_done"], status["progress"]["tiles_total"])
        self.assertEqual(status["progress"]["tiles_total"], 4 * 3)

        # The whole event history is replayed to a late reader, with increasing ids.
        events = list(self.client.events(job_id))
        self.assertEqual(events[-1].type, "done")
        ids = [int(event.id) for event in events]
        self.assertEqual(ids, sorted(ids))
        self.assertEqual(len(set(ids)), len(ids))
        tiles = [event for event in events if event.type == "tile" and not event.data.get("preview")]
        self.assertEqual(len(tiles), 12)
        x0, y0, x1, y1 = tiles[0].data["rect"]
        self.assertEqual((x1 - x0, y1 - y0), (16, 16))
        self.assertIn("/tiles/", tiles[0].data["url"])

        # Last-Event-ID resumes after the given event.
        resumed = list(self.client.events(job_id, last_event_id=events[2].id))
        self.assertEqual([e.id for e in resumed], [e.id for e in events[3:]])

        # wait's on_event saw each event once, in order, up to the end of the job.
        self.assertTrue(seen)
        self.assertEqual([e.id for e in seen], [e.id for e in events[-len(seen):]])
        self.assertIn("progress", [e.type for e in seen])

        tile = self.client.tile(job_id, 0, 0)
        self.assertEqual(tile[:4], EXR_MAGIC)

        path = self.client.fetch_image(job_id, self.path("image.exr"))
        with open(path, "rb") as image:
            data = image.read()
        self.assertEqual(data[:4], EXR_MAGIC)
        self.assertGreater(len(data), 1000)
        self.assertFalse(os.path.exists(path + ".part"))

        self.assertIn(job_id, [job["id"] for job in self.client.jobs()])

    def test_fetch_image_waits_longer_than_the_client_timeout(self):
        # ?wait=true answers only when the job ends: the client's read timeout must not apply.
        # Only the waiting download uses the short timeout: the other requests answer at once,
        # but on a loaded machine (CI runs tests in parallel) "at once" can exceed 0.3 s.
        client = PhotondClient(self.daemon.url, timeout=0.3)
        job_id = self.client.submit({
            "scene": {"builtin": "cornell-box"}, "integrator": "path",
            "image": {"width": 64, "height": 48, "spp": 256, "tile_size": 16}})
        started = time.monotonic()
        path = client.fetch_image(job_id, self.path("slow.exr"))
        self.assertGreater(time.monotonic() - started, 0.3, "the job was too fast to tell")
        with open(path, "rb") as image:
            self.assertEqual(image.read(4), EXR_MAGIC)
        with open(self.client.fetch_preview(job_id, self.path("slow.png")), "rb") as preview:
            self.assertEqual(preview.read(8), b"\x89PNG\r\n\x1a\n")

    def test_second_view_hits_the_photon_map_cache(self):
        # Photon counts no other test uses, so that the first view is a miss here.
        first = small_job(look_from=[0, 2.75, 10.75], look_at=[0, 2.75, 0])
        first["photons"] = {"global": 3000, "caustic": 1500, "seed": 7}
        second = json.loads(json.dumps(first))
        second["camera"]["look_from"] = [1.5, 3.0, 10.0]
        first_status = self.client.wait(self.client.submit(first), timeout=60)
        second_status = self.client.wait(self.client.submit(second), timeout=60)
        self.assertEqual(first_status["state"], "done", first_status)
        self.assertEqual(second_status["state"], "done", second_status)
        self.assertEqual(first_status["photons"]["cache"], "miss")
        self.assertEqual(second_status["photons"]["cache"], "hit")
        self.assertEqual(second_status["timings"].get("photon_tracing", 0.0), 0.0)

    def test_batch_views_and_caches_move_to_another_daemon(self):
        job = small_job()
        job.pop("camera", None)
        job["integrator"] = "photon-map"
        job["photons"] = {"global": 2000, "caustic": 1000, "seed": 11}
        cameras = [{"look_from": [0, 2.75, 10.75], "look_at": [0, 2.75, 0]},
                   {"look_from": [1.5, 3.0, 10.0], "look_at": [0, 2.75, 0]}]
        ids = self.client.submit_batch(job, cameras)
        self.assertEqual(len(ids), 2)
        views = [self.client.wait(job_id, timeout=60) for job_id in ids]
        for view in views:
            self.assertEqual(view["state"], "done", view)
        first_cache = views[0]["statistics"]["irradiance_cache"]
        self.assertEqual(views[1]["statistics"]["irradiance_cache"]["start_from"], first_cache["key"])
        # Both artifacts of the first view to a second daemon: its job takes them.
        maps = self.client.export_cache("photon-maps", views[0]["photons"]["key"], self.path("maps.pm"))
        cache = self.client.export_cache("render-caches", first_cache["key"], self.path("view.rc"))
        os.makedirs(os.path.join(self.directory, "other"), exist_ok=True)
        other = Daemon(os.path.join(self.directory, "other"))
        try:
            remote = PhotondClient(other.url)
            self.assertTrue(remote.import_cache("photon-maps", views[0]["photons"]["key"], maps))
            self.assertTrue(remote.import_cache("render-caches", first_cache["key"], cache))
            self.assertFalse(remote.import_cache("render-caches", first_cache["key"], cache))
            single = dict(job, camera=cameras[0])
            status = remote.wait(remote.submit(single), timeout=60)
            self.assertEqual(status["photons"]["cache"], "hit")
            self.assertEqual(status["statistics"]["irradiance_cache"]["cache"], "hit")
        finally:
            other.stop()
        with self.assertRaises(PhotondError) as refused:
            self.client.submit_batch(job, [{"vfov_deg": 500}])
        self.assertEqual(refused.exception.field, "cameras[0].look_from")

    def test_example_script_renders_views(self):
        out_dir = self.path("views")
        result = subprocess.run(
            [sys.executable, os.path.join(SOURCE_DIR, "clients", "python",
                                          "example_render_views.py"),
             "--server", self.daemon.url, "--views", "2", "--width", "64", "--height", "48",
             "--out-dir", out_dir],
            capture_output=True, text=True, timeout=120)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertEqual(len(lines), 3, result.stdout)
        self.assertIn("hit", lines[2], result.stdout)
        for name in ("front", "left"):
            with open(os.path.join(out_dir, f"{name}.exr"), "rb") as image:
                self.assertEqual(image.read(4), EXR_MAGIC)

    def test_idempotency_key_returns_the_same_job(self):
        first = self.client.submit(small_job(), idempotency_key="python-client-test-key")
        again = self.client.submit(small_job(), idempotency_key="python-client-test-key")
        self.assertEqual(first, again)
        self.client.wait(first, timeout=60)

    def test_cancel(self):
        job_id = self.client.submit({
            "scene": {"builtin": "cornell-box"}, "integrator": "path",
            "image": {"width": 512, "height": 512, "spp": 4096, "tile_size": 8}})
        self.client.cancel(job_id)
        started = time.monotonic()
        status = self.client.wait(job_id, timeout=30)
        self.assertEqual(status["state"], "cancelled", status)
        self.assertLess(time.monotonic() - started, 10)
        with self.assertRaises(PhotondError) as raised:
            self.client.fetch_image(job_id, self.path("cancelled.exr"), wait=False)
        self.assertGreaterEqual(raised.exception.status, 400)
        self.assertFalse(os.path.exists(self.path("cancelled.exr")))

    def test_problem_names_the_field(self):
        job = small_job()
        job["image"]["sppp"] = 2
        with self.assertRaises(PhotondError) as raised:
            self.client.submit(job)
        error = raised.exception
        self.assertGreaterEqual(error.status, 400)
        self.assertLess(error.status, 500)
        self.assertEqual(error.field, "image.sppp")
        self.assertTrue(error.title)
        self.assertIn("(field: image.sppp)", str(error))

        with self.assertRaises(PhotondError) as missing:
            self.client.status("no-such-job")
        self.assertEqual(missing.exception.status, 404)

    def test_upload_scene(self):
        scene_id = self.client.upload_scene(os.path.join(TEST_DATA, "gltf", "textured_quad.glb"))
        self.assertTrue(scene_id.startswith("sha256:"), scene_id)
        job = small_job()
        job["scene"] = {"id": scene_id}
        status = self.client.wait(self.client.submit(job), timeout=60)
        self.assertEqual(status["state"], "done", status)

        with self.assertRaises(PhotondError) as raised:
            self.client.upload_scene(os.path.join(TEST_DATA, "gltf", "broken", "invalid_json.gltf"))
        self.assertGreaterEqual(raised.exception.status, 400)
        self.assertLess(raised.exception.status, 500)

    def test_unreachable_server(self):
        with self.assertRaises(PhotondError) as raised:
            PhotondClient("http://127.0.0.1:1").jobs()
        self.assertEqual(raised.exception.status, 0)
        self.assertIn("http://127.0.0.1:1", str(raised.exception))


if __name__ == "__main__":
    if len(sys.argv) > 1 and os.path.isdir(sys.argv[1]):
        BINARY_DIR = sys.argv.pop(1)
        PHOTOND = os.path.join(BINARY_DIR, "server", "photond")
    unittest.main()
