#!/usr/bin/env python3
"""The Python client as a package: `pip install --no-index --no-build-isolation clients/python`
into a fresh virtual environment (Debian's setuptools and wheel seen through
--system-site-packages; nothing is downloaded), then the installed `photond-submit` against a
real daemon on a free loopback port (with a bearer token, and a scene root holding a glTF file
that fails its job). Run by ctest as `python_package`, with PHOTOND_BINARY_DIR set to the build
directory (or pass it as the first argument).

The virtual environment is made with /usr/bin/python3 (Debian's Python, as on CI) when it can
build the package offline (venv with pip, setuptools and wheel), else with the Python running
this test when that one can (a pyenv Python usually has no wheel)."""

import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_python_client  # noqa: E402
from test_python_client import EXR_MAGIC, SMALL_JOB, SOURCE_DIR, Daemon  # noqa: E402

PACKAGE_SOURCE = os.path.join(SOURCE_DIR, "clients", "python")
TEST_GLTF = os.path.join(SOURCE_DIR, "tests", "data", "gltf")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
TOKEN = "python-package-test-token"


BUILD_MODULES = "import ensurepip, venv, setuptools.build_meta, wheel.bdist_wheel"
DEBIAN_PACKAGES = "python3-venv python3-pip python3-setuptools python3-wheel"


def base_python():
    """The first Python that can make a venv and build the package without an index."""
    candidates = [python for python in ("/usr/bin/python3", sys.executable)
                  if os.access(python, os.X_OK)]
    for python in dict.fromkeys(candidates):
        probe = subprocess.run([python, "-c", BUILD_MODULES], capture_output=True,
                               env=clean_environment(), timeout=60)
        if probe.returncode == 0:
            return python
    raise RuntimeError(f"none of {', '.join(candidates)} can build the package offline "
                       f"(`{BUILD_MODULES}` failed; on Debian: apt-get install {DEBIAN_PACKAGES})")


def clean_environment(**extra):
    """The environment without the caller's pip and Python settings (a find-links directory,
    an index, a PYTHONPATH that would hide what the venv installed)."""
    environment = {name: value for name, value in os.environ.items()
                   if not name.startswith(("PIP_", "PYTHON", "PHOTOND_", "VIRTUAL_ENV"))}
    environment.update(PIP_CONFIG_FILE=os.devnull, PIP_NO_INPUT="1",
                       PIP_DISABLE_PIP_VERSION_CHECK="1", PYTHONDONTWRITEBYTECODE="1")
    environment.update(extra)
    return environment


def run(command, timeout=120, **kwargs):
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout, **kwargs)


def exr_data_window(data):
    """(xmin, ymin, xmax, ymax) of a single-part OpenEXR file's header, and its channel names."""
    if data[:4] != EXR_MAGIC:
        raise ValueError("not an OpenEXR file")
    offset = 8
    window, channels = None, []
    while data[offset] != 0:
        name_end = data.index(b"\0", offset)
        type_end = data.index(b"\0", name_end + 1)
        name = data[offset:name_end].decode("ascii")
        attribute_type = data[name_end + 1:type_end].decode("ascii")
        (size,) = struct.unpack_from("<i", data, type_end + 1)
        value = data[type_end + 5:type_end + 5 + size]
        if name == "dataWindow" and attribute_type == "box2i":
            window = struct.unpack("<4i", value)
        elif name == "channels" and attribute_type == "chlist":
            position = 0
            while value[position] != 0:
                end = value.index(b"\0", position)
                channels.append(value[position:end].decode("ascii"))
                position = end + 1 + 16  # pixel type, pLinear + reserved, xSampling, ySampling
        offset = type_end + 5 + size
    if window is None:
        raise ValueError("no dataWindow in the header")
    return window, channels


def png_size(data):
    if data[:8] != PNG_MAGIC or data[12:16] != b"IHDR":
        raise ValueError("not a PNG file")
    return struct.unpack(">II", data[16:24])


class PythonPackageTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = tempfile.mkdtemp(prefix="photond_python_package_")
        try:
            cls.install()
            token_file = os.path.join(cls.directory, "token")
            with open(token_file, "w", encoding="utf-8") as out:
                out.write(TOKEN + "\n")
            cls.token_file = token_file
            cls.daemon = Daemon(cls.directory, ["--token-file", token_file,
                                                "--scene-root", TEST_GLTF])
        except BaseException:
            shutil.rmtree(cls.directory, ignore_errors=True)
            raise

    @classmethod
    def install(cls):
        # pip builds a local directory in place (build/, *.egg-info): build a copy, so that the
        # source tree stays clean.
        source = os.path.join(cls.directory, "source")
        shutil.copytree(PACKAGE_SOURCE, source, ignore=shutil.ignore_patterns(
            "build", "*.egg-info", "__pycache__", "*.pyc"))
        cls.venv = os.path.join(cls.directory, "venv")
        python = base_python()
        made = run([python, "-m", "venv", "--system-site-packages", cls.venv],
                   env=clean_environment())
        if made.returncode != 0:
            raise RuntimeError(f"{python} -m venv failed (Debian: {DEBIAN_PACKAGES}):\n"
                               f"{made.stdout}{made.stderr}")
        cls.python = os.path.join(cls.venv, "bin", "python")
        installed = run([cls.python, "-m", "pip", "install", "--no-index", "--no-cache-dir",
                         "--no-build-isolation", source], timeout=300, env=clean_environment())
        if installed.returncode != 0:
            raise RuntimeError("pip install --no-index --no-build-isolation clients/python "
                               f"failed with {python} (Debian: {DEBIAN_PACKAGES}):\n"
                               f"{installed.stdout}{installed.stderr}")
        cls.submit_command = os.path.join(cls.venv, "bin", "photond-submit")

    @classmethod
    def tearDownClass(cls):
        cls.daemon.stop()
        shutil.rmtree(cls.directory, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.directory, name)

    def write_job(self, name, job):
        path = self.path(name)
        with open(path, "w", encoding="utf-8") as out:
            json.dump(job, out)
        return path

    def submit(self, *arguments, stdin=None, server=True, token=True, **environment):
        """The installed photond-submit, run from a directory outside the source tree."""
        command = [self.submit_command]
        if server:
            command += ["--server", self.daemon.url]
        if token:
            command += ["--token-file", self.token_file]
        return run(command + list(arguments), input=stdin, cwd=self.directory,
                   env=clean_environment(**environment))

    def server_bytes(self, path):
        request = urllib.request.Request(self.daemon.url + path,
                                         headers={"Authorization": "Bearer " + TOKEN})
        with urllib.request.urlopen(request, timeout=60) as response:
            return response.read()

    def test_the_installed_package_is_the_venvs_typed_and_dependency_free(self):
        probe = run([self.python, "-c", (
            "import json, os, sys, importlib.metadata as m, photond_client, photond_client.submit\n"
            "print(json.dumps({'file': photond_client.__file__, 'prefix': sys.prefix,\n"
            "  'version': photond_client.__version__,\n"
            "  'metadata_version': m.version('photond-client'),\n"
            "  'requires': m.requires('photond-client'),\n"
            "  'scripts': [e.value for e in m.entry_points(group='console_scripts')\n"
            "              if e.name == 'photond-submit'],\n"
            "  'typed': os.path.isfile(os.path.join(os.path.dirname(photond_client.__file__),\n"
            "                                       'py.typed'))}))")],
            cwd=self.directory, env=clean_environment())
        self.assertEqual(probe.returncode, 0, probe.stderr)
        found = json.loads(probe.stdout)
        self.assertTrue(found["file"].startswith(os.path.join(self.venv, "lib")), found)
        self.assertEqual(os.path.realpath(found["prefix"]), os.path.realpath(self.venv))
        self.assertEqual(found["version"], found["metadata_version"])
        self.assertFalse(found["requires"], "runtime dependencies beyond the standard library")
        self.assertEqual(found["scripts"], ["photond_client.submit:main"])
        self.assertTrue(found["typed"], "py.typed is not installed")
        self.assertTrue(os.access(self.submit_command, os.X_OK))

    def test_submit_writes_the_exr_and_the_preview(self):
        job = self.write_job("job.json", SMALL_JOB)
        out, preview = self.path("out.exr"), self.path("out.png")
        # --set as photonctl's: the width below is the job's, 64 in the file.
        result = self.submit(job, "-o", out, "--preview", preview, "--set", "image.width=80")
        self.assertEqual(result.returncode, 0, result.stderr)
        job_id = result.stdout.strip()
        self.assertEqual(result.stdout, job_id + "\n")
        self.assertIn(f"job {job_id}: running: render", result.stderr)
        self.assertIn(f"job {job_id}: done", result.stderr)

        with open(out, "rb") as image:
            data = image.read()
        self.assertEqual(data[:4], EXR_MAGIC)
        window, channels = exr_data_window(data)
        self.assertEqual(window, (0, 0, 79, 47))
        self.assertTrue({"R", "G", "B"} <= set(channels), channels)
        # The whole image, as the daemon serves it.
        self.assertEqual(data, self.server_bytes(f"/v1/jobs/{job_id}/image.exr"))
        self.assertFalse(os.path.exists(out + ".part"))
        with open(preview, "rb") as image:
            self.assertEqual(png_size(image.read()), (80, 48))

    def test_submit_reads_stdin_and_the_environment(self):
        out = self.path("stdin.exr")
        job = dict(SMALL_JOB, image=dict(SMALL_JOB["image"], width=32, height=32))
        result = self.submit("-", "-o", out, "--quiet", stdin=json.dumps(job), server=False,
                             token=False, PHOTOND_URL=self.daemon.url,
                             PHOTOND_TOKEN_FILE=self.token_file)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(result.stderr, "")
        with open(out, "rb") as image:
            self.assertEqual(exr_data_window(image.read())[0], (0, 0, 31, 31))

        # Without the token the daemon refuses the job, and the command says why.
        refused = self.submit("-", "-o", self.path("refused.exr"), stdin=json.dumps(job),
                              token=False)
        self.assertEqual(refused.returncode, 1)
        self.assertIn("photond-submit: Unauthorized", refused.stderr)
        self.assertFalse(os.path.exists(self.path("refused.exr")))

    def test_a_job_the_daemon_refuses_exits_1_naming_the_field(self):
        out = self.path("refused_field.exr")
        result = self.submit(self.write_job("job.json", SMALL_JOB), "-o", out,
                             "--set", "image.sppp=2")
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertEqual(result.stdout, "")
        self.assertRegex(result.stderr, r"^photond-submit: .*\(field: image\.sppp\)\n$")
        self.assertFalse(os.path.exists(out))

    def test_a_job_that_fails_exits_1_with_its_error(self):
        job = dict(SMALL_JOB, scene={"path": "broken/invalid_json.gltf"})
        out = self.path("failed.exr")
        result = self.submit(self.write_job("failed.json", job), "-o", out, "--preview",
                             self.path("failed.png"))
        self.assertEqual(result.returncode, 1, result.stderr)
        job_id = result.stdout.strip()
        self.assertTrue(job_id, "no job id on stdout")
        self.assertIn(f"photond-submit: job {job_id} failed: ", result.stderr)
        self.assertIn("invalid_json.gltf: cannot load glTF", result.stderr)
        self.assertFalse(os.path.exists(out))
        self.assertFalse(os.path.exists(self.path("failed.png")))

    def test_failures_before_submitting(self):
        job = self.write_job("job.json", SMALL_JOB)
        cases = [
            (["--server", "http://127.0.0.1:1", job, "-o", self.path("a.exr")],
             None, "cannot connect to the server at http://127.0.0.1:1"),
            ([job, "-o", os.path.join(self.directory, "missing", "a.exr")],
             None, "does not exist"),
            (["-", "-o", self.path("a.exr")], '{"scene": \n {', "stdin: malformed JSON at line 2"),
            ([self.path("no-such-job.json"), "-o", self.path("a.exr")], None,
             "no-such-job.json: cannot read"),
            ([job, "-o", self.path("a.exr"), "--set", "image"], None, "expected FIELD=VALUE"),
        ]
        for arguments, stdin, message in cases:
            with self.subTest(message=message):
                result = self.submit(*arguments, stdin=stdin, server="--server" not in arguments)
                self.assertEqual(result.returncode, 1, result.stderr)
                self.assertIn(message, result.stderr)
                self.assertTrue(result.stderr.startswith("photond-submit: "), result.stderr)
                self.assertEqual(result.stdout, "")
        self.assertFalse(os.path.exists(self.path("a.exr")))
        usage = self.submit(job)  # no -o
        self.assertEqual(usage.returncode, 2)
        self.assertIn("-o/--output", usage.stderr)

    def test_timeout_exits_1_and_leaves_the_job_running(self):
        job = {"scene": {"builtin": "cornell-box"}, "integrator": "path",
               "image": {"width": 256, "height": 256, "spp": 4096, "tile_size": 8}}
        result = self.submit(self.write_job("long.json", job), "-o", self.path("long.exr"),
                             "--timeout", "0.5")
        job_id = result.stdout.strip()
        try:
            self.assertEqual(result.returncode, 1, result.stderr)
            self.assertIn(f"job {job_id} did not finish within 0.5 s", result.stderr)
            self.assertFalse(os.path.exists(self.path("long.exr")))
        finally:
            if job_id:
                request = urllib.request.Request(
                    f"{self.daemon.url}/v1/jobs/{job_id}", method="DELETE",
                    headers={"Authorization": "Bearer " + TOKEN})
                urllib.request.urlopen(request, timeout=30).close()


if __name__ == "__main__":
    if len(sys.argv) > 1 and os.path.isdir(sys.argv[1]):
        test_python_client.BINARY_DIR = sys.argv.pop(1)
        test_python_client.PHOTOND = os.path.join(test_python_client.BINARY_DIR, "server",
                                                  "photond")
    unittest.main()
