#!/usr/bin/env python3
"""Checks deploy/ (systemd unit, Dockerfile, Kubernetes manifests, farm notes) against the
photond binary, for what no linter checks. Problems are reported by name and make it exit 1.

    python3 tests/deploy/check_deploy.py build/server/photond [--static]

Needs Python 3 and, for the Kubernetes YAML, PyYAML (Debian: python3-yaml). Optional tools it
uses when they are there (it says SKIP otherwise): systemd-analyze (Debian: systemd) for
`verify` and `security --offline`, libseccomp (libseccomp2, always on Debian) to run the unit's
command line under its system-call filter, readelf/dpkg for the image's runtime packages.
Unless --static is given it also starts things with the built binary (about 20 s on 2 cores):
  - the unit's ExecStart lines (the default and the drop-in's), paths moved to a temporary
    directory and port 0, as user nobody when run as root, under the unit's SystemCallFilter
    (@system-service minus @privileged), MemoryDenyWriteExecute rules, RestrictAddressFamilies,
    NoNewPrivileges, UMask and LimitNOFILE: /healthz, /readyz, the token, a small render, a
    clean SIGTERM (exit 0);
  - the Dockerfile's ENTRYPOINT the same way (without its token file it must exit 2), and its
    health-check script against that daemon and against a closed port;
  - the three steps of deploy/kubernetes/render-regions.yaml as their shell scripts, the
    assembled frame byte-identical to `photond render` of the whole view.
"""

import ctypes
import ctypes.util
import fnmatch
import json
import os
import re
import select
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import urllib.error
import urllib.request

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
DEPLOY = os.path.join(REPO, "deploy")
UNIT = os.path.join(DEPLOY, "systemd", "photond.service")
DROPIN = os.path.join(DEPLOY, "systemd", "listen-beyond-loopback.conf")
DOCKERFILE = os.path.join(DEPLOY, "docker", "Dockerfile")
DOCKERIGNORE = os.path.join(DEPLOY, "docker", "Dockerfile.dockerignore")
HEALTHCHECK = os.path.join(DEPLOY, "docker", "healthcheck.sh")
K8S_DAEMON = os.path.join(DEPLOY, "kubernetes", "daemon.yaml")
K8S_REGIONS = os.path.join(DEPLOY, "kubernetes", "render-regions.yaml")
FARMS = os.path.join(DEPLOY, "farms.md")

# Libraries every debian:bookworm-slim image already has (apt itself needs them).
BASE_IMAGE_PACKAGES = {"libc6", "libgcc-s1", "libstdc++6", "zlib1g"}
EXR_MAGIC = b"\x76\x2f\x31\x01"

problems = []


def problem(where, message):
    problems.append(f"{os.path.relpath(where, REPO) if os.path.isabs(where) else where}: {message}")
    print(f"FAIL {problems[-1]}", flush=True)


def ok(message):
    print(f"ok   {message}", flush=True)


def skip(message):
    print(f"SKIP {message}", flush=True)


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


# --------------------------------------------------------------------------------------------
# The binary's own flags

def help_flags(photond, command):
    """Every --flag (and -o) that `photond COMMAND --help` names."""
    out = subprocess.run([photond, command, "--help"], capture_output=True, text=True, timeout=30)
    if out.returncode != 0:
        problem(photond, f"`{command} --help` exited {out.returncode}")
        return set()
    flags = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", out.stdout))
    if re.search(r"(?<![\w-])-o\b", out.stdout):
        flags.add("-o")
    return flags


def used_flags(argv):
    return [a for a in argv if re.fullmatch(r"--?[A-Za-z][\w-]*", a)]


def flag_value(argv, flag):
    for i, a in enumerate(argv[:-1]):
        if a == flag:
            return argv[i + 1]
    return None


def check_flags(where, argv, known, command):
    unknown = [f for f in used_flags(argv) if f not in known]
    if unknown:
        problem(where, f"`photond {command}` has no flag {', '.join(unknown)} (photond {command} --help)")
    return not unknown


def split_listen(value):
    """"HOST:PORT" or "[V6]:PORT" -> (host, port)."""
    m = re.fullmatch(r"\[([^\]]+)\]:(\d+)", value) or re.fullmatch(r"([^:]*):(\d+)", value)
    if not m:
        return None, None
    return (m.group(1) or "127.0.0.1"), int(m.group(2))


def is_loopback(host):
    return host == "localhost" or host.startswith("127.") or host == "::1"


# --------------------------------------------------------------------------------------------
# systemd

def parse_unit(path):
    """{section: [(key, value), ...]} keeping repeated keys in order; continuation lines joined."""
    sections, section, pending = {}, None, ""
    for raw in read(path).splitlines():
        line = pending + raw.strip() if pending else raw.strip()
        pending = ""
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        if not line or line[0] in "#;":
            continue
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1]
            sections.setdefault(section, [])
            continue
        key, _, value = line.partition("=")
        sections.setdefault(section, []).append((key.strip(), value.strip()))
    return sections


def unit_values(sections, section, key):
    """The effective list of a key's values: an empty assignment resets it (systemd's rule)."""
    values = []
    for k, v in sections.get(section, []):
        if k == key:
            values = [] if v == "" else values + [v]
    return values


def last(values):
    return values[-1] if values else None


def merged_unit(*paths):
    merged = {}
    for path in paths:
        for section, items in parse_unit(path).items():
            merged.setdefault(section, []).extend(items)
    return merged


REQUIRED_SERVICE = {
    "DynamicUser": "yes", "ProtectSystem": "strict", "ProtectHome": "yes", "PrivateTmp": "yes",
    "NoNewPrivileges": "yes", "Restart": "on-failure", "MemoryDenyWriteExecute": "yes",
}


def check_unit_command(where, sections, serve_flags, *, expect_loopback):
    """ExecStart: photond serve with known flags, its paths backed by StateDirectory=, the token
    from LoadCredential= when listening beyond loopback. Returns argv."""
    exec_start = unit_values(sections, "Service", "ExecStart")
    if len(exec_start) != 1:
        problem(where, f"expected one effective ExecStart=, found {len(exec_start)}")
        return None
    argv = shlex.split(exec_start[0])
    if argv[:2] != ["/usr/local/bin/photond", "serve"]:
        problem(where, f"ExecStart should run `/usr/local/bin/photond serve`, runs {' '.join(argv[:2])}")
        return None
    check_flags(where, argv[2:], serve_flags, "serve")
    state_dirs = set(" ".join(unit_values(sections, "Service", "StateDirectory")).split())
    if "photond" not in state_dirs:
        problem(where, "StateDirectory= should hold photond (the cache directory)")
    if flag_value(argv, "--cache-dir") != "/var/lib/photond":
        problem(where, "ExecStart should give --cache-dir /var/lib/photond")
    for flag in ("--cache-dir", "--scene-root"):
        value = flag_value(argv, flag)
        if value and value.startswith("/var/lib/") and value[len("/var/lib/"):] not in state_dirs:
            problem(where, f"{flag} {value} is not a StateDirectory= (ProtectSystem=strict makes it unwritable or missing)")
    listen = flag_value(argv, "--listen") or "127.0.0.1:8080"
    host, port = split_listen(listen)
    if host is None:
        problem(where, f"--listen {listen} is not HOST:PORT")
        return argv
    token = flag_value(argv, "--token-file")
    if expect_loopback and not is_loopback(host):
        problem(where, f"the default unit should listen on loopback, listens on {listen}")
    if not is_loopback(host):
        credentials = {c.split(":", 1)[0] for c in unit_values(sections, "Service", "LoadCredential")}
        m = re.fullmatch(r"\$\{CREDENTIALS_DIRECTORY\}/([\w.-]+)", token or "")
        if not m:
            problem(where, f"listening on {listen} needs --token-file ${{CREDENTIALS_DIRECTORY}}/NAME")
        elif m.group(1) not in credentials:
            problem(where, f"--token-file names credential {m.group(1)}, but no LoadCredential={m.group(1)}:... hands it over")
    limit = last(unit_values(sections, "Service", "LimitNOFILE"))
    http_threads = int(flag_value(argv, "--http-threads") or 1024)
    if not limit or not limit.split(":")[-1].isdigit() or int(limit.split(":")[0]) < http_threads + 1024:
        problem(where, f"LimitNOFILE= should leave room for --http-threads {http_threads} connections "
                       f"plus cache files (at least {http_threads + 1024}), is {limit}")
    return argv


def check_unit_static(photond, serve_flags):
    base = parse_unit(UNIT)
    text = read(UNIT)
    for key, want in REQUIRED_SERVICE.items():
        got = last(unit_values(base, "Service", key))
        if got != want:
            problem(UNIT, f"{key}={want} expected, found {key}={got}")
    if unit_values(base, "Service", "CapabilityBoundingSet") != [] or \
            not any(k == "CapabilityBoundingSet" for k, _ in base.get("Service", [])):
        problem(UNIT, "CapabilityBoundingSet= (empty: no capabilities) expected")
    families = set(" ".join(unit_values(base, "Service", "RestrictAddressFamilies")).split())
    if families != {"AF_INET", "AF_INET6", "AF_UNIX"}:
        problem(UNIT, f"RestrictAddressFamilies=AF_INET AF_INET6 AF_UNIX expected, found {sorted(families)}")
    filters = unit_values(base, "Service", "SystemCallFilter")
    if not filters or "@system-service" not in filters[0].split():
        problem(UNIT, "SystemCallFilter=@system-service expected (first, as the allow list)")
    if "LoadCredential" in dict(base.get("Service", [])):
        problem(UNIT, "the default unit listens on loopback without a token: LoadCredential= belongs in the drop-in")
    for probe in ("/readyz", "/healthz"):
        if probe not in text:
            problem(UNIT, f"the health-probe note should name {probe}")
    if "listen-beyond-loopback.conf" not in text:
        problem(UNIT, "the header should say how to listen beyond loopback (listen-beyond-loopback.conf)")
    default_argv = check_unit_command(UNIT, base, serve_flags, expect_loopback=True)
    dropin_argv = check_unit_command(DROPIN, merged_unit(UNIT, DROPIN), serve_flags, expect_loopback=False)
    if default_argv and dropin_argv:
        ok("systemd unit: hardening keys, ExecStart flags, StateDirectory, LimitNOFILE, drop-in token credential")
    return base, default_argv, dropin_argv


def systemd_analyze(photond):
    tool = shutil.which("systemd-analyze")
    if not tool:
        skip("systemd-analyze is not installed (Debian: systemd): unit not verified")
        return
    with tempfile.TemporaryDirectory(prefix="photond-unit.") as tmp:
        binary = os.path.abspath(photond)
        os.makedirs(os.path.join(tmp, "photond.service.d"))
        unit = os.path.join(tmp, "photond.service")
        with open(unit, "w") as f:
            f.write(read(UNIT).replace("/usr/local/bin/photond", binary))
        with open(os.path.join(tmp, "photond.service.d", "listen.conf"), "w") as f:
            f.write(read(DROPIN).replace("/usr/local/bin/photond", binary))
        out = subprocess.run([tool, "verify", unit], capture_output=True, text=True, timeout=120)
        report = (out.stdout + out.stderr).strip()
        if out.returncode != 0 or report:
            problem(UNIT, f"systemd-analyze verify (with the drop-in, ExecStart at {binary}) "
                          f"exited {out.returncode}: {report}")
        else:
            ok("systemd-analyze verify photond.service + listen-beyond-loopback.conf: clean")
        # Exposure: 0 (locked down) to 10; --threshold is in tenths.
        out = subprocess.run([tool, "security", "--offline=yes", "--threshold=20", unit],
                             capture_output=True, text=True, timeout=120)
        level = re.search(r"Overall exposure level for \S+: ([\d.]+)", out.stdout)
        if "--offline" in out.stderr or not level:
            skip(f"systemd-analyze security --offline is not supported here: {out.stderr.strip()[:200]}")
        elif out.returncode != 0:
            problem(UNIT, f"systemd-analyze security: exposure {level.group(1)}, above 2.0")
        else:
            ok(f"systemd-analyze security --offline: exposure {level.group(1)} (at most 2.0)")


# --------------------------------------------------------------------------------------------
# Running a command line the way the unit would: seccomp through libseccomp (ctypes)

SCMP_ACT_KILL_PROCESS = 0x80000000
SCMP_ACT_ALLOW = 0x7FFF0000
SCMP_CMP_EQ, SCMP_CMP_GT, SCMP_CMP_MASKED_EQ = 4, 6, 7
PROT_WRITE, PROT_EXEC, SHM_EXEC = 0x2, 0x4, 0o100000
EPERM, EAFNOSUPPORT = 1, 97
AF_NAMES = {"AF_UNIX": 1, "AF_INET": 2, "AF_INET6": 10}


class ScmpArgCmp(ctypes.Structure):
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int),
                ("datum_a", ctypes.c_uint64), ("datum_b", ctypes.c_uint64)]


def libseccomp():
    try:
        lib = ctypes.CDLL(ctypes.util.find_library("seccomp") or "libseccomp.so.2", use_errno=True)
    except OSError:
        return None
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int,
                                           ctypes.c_uint, ctypes.POINTER(ScmpArgCmp)]
    lib.seccomp_load.argtypes = [ctypes.c_void_p]
    return lib


def syscall_groups():
    """systemd-analyze syscall-filter: {"@group": [entries]}."""
    out = subprocess.run(["systemd-analyze", "syscall-filter"], capture_output=True, text=True, timeout=60)
    groups, current = {}, None
    for line in out.stdout.splitlines():
        if line.startswith("@"):
            current = groups.setdefault(line.strip(), [])
        elif current is not None and line.strip() and not line.strip().startswith("#"):
            current.append(line.strip())
    return groups


def expand(groups, names, seen=None):
    seen = set() if seen is None else seen
    result = set()
    for name in names:
        if name.startswith("@"):
            if name not in seen:
                seen.add(name)
                result |= expand(groups, groups.get(name, []), seen)
        else:
            result.add(name)
    return result


def sandbox_spec(sections):
    """What the launcher applies, from the unit: the allowed system calls, address families,
    MemoryDenyWriteExecute, LimitNOFILE, UMask."""
    groups = syscall_groups()
    allowed = set()
    for entry in unit_values(sections, "Service", "SystemCallFilter"):
        names = entry.split()
        if names and names[0].startswith("~"):
            allowed -= expand(groups, [names[0][1:]] + names[1:])
        else:
            allowed |= expand(groups, names)
    limit = last(unit_values(sections, "Service", "LimitNOFILE"))
    return {
        "syscalls": sorted(allowed),
        "families": [AF_NAMES[f] for f in " ".join(unit_values(sections, "Service", "RestrictAddressFamilies")).split()],
        "mdwe": last(unit_values(sections, "Service", "MemoryDenyWriteExecute")) == "yes",
        "nofile": int(limit.split(":")[-1]) if limit else None,
        "umask": int(last(unit_values(sections, "Service", "UMask")) or "0022", 8),
    }


def sandbox_exec(spec_path, argv):
    """Runs in the launcher process (--sandbox-exec): applies the spec, then execs argv."""
    with open(spec_path) as f:
        spec = json.load(f)
    import resource
    if spec.get("nofile"):
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (spec["nofile"], spec["nofile"]))
        except (ValueError, OSError):  # no CAP_SYS_RESOURCE here: as many as the hard limit allows
            hard = resource.getrlimit(resource.RLIMIT_NOFILE)[1]
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
    os.umask(spec["umask"])
    if spec.get("uid") is not None:
        os.setgroups([])
        os.setgid(spec["gid"])
        os.setuid(spec["uid"])
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(38, 1, 0, 0, 0) != 0:  # PR_SET_NO_NEW_PRIVS
        sys.exit("sandbox: PR_SET_NO_NEW_PRIVS failed")
    lib = libseccomp()

    def rule(ctx, action, name, *cmps):
        number = lib.seccomp_syscall_resolve_name(name.encode())
        if number < 0:
            return
        array = (ScmpArgCmp * max(1, len(cmps)))(*cmps)
        if lib.seccomp_rule_add_array(ctx, action, number, len(cmps), array) != 0:
            sys.exit(f"sandbox: seccomp rule for {name} refused")

    # Filter 1 (MemoryDenyWriteExecute as systemd 252 does it, RestrictAddressFamilies), loaded
    # first: the allow list loaded after it does not allow seccomp() itself.
    ctx = lib.seccomp_init(SCMP_ACT_ALLOW)
    if spec["mdwe"]:
        deny = 0x00050000 | EPERM
        rule(ctx, deny, "mmap", ScmpArgCmp(2, SCMP_CMP_MASKED_EQ, PROT_EXEC | PROT_WRITE, PROT_EXEC | PROT_WRITE))
        rule(ctx, deny, "mprotect", ScmpArgCmp(2, SCMP_CMP_MASKED_EQ, PROT_EXEC, PROT_EXEC))
        rule(ctx, deny, "pkey_mprotect", ScmpArgCmp(2, SCMP_CMP_MASKED_EQ, PROT_EXEC, PROT_EXEC))
        rule(ctx, deny, "shmat", ScmpArgCmp(2, SCMP_CMP_MASKED_EQ, SHM_EXEC, SHM_EXEC))
    if spec["families"]:
        deny = 0x00050000 | EAFNOSUPPORT
        top = max(spec["families"])
        for family in range(0, top):
            if family not in spec["families"]:
                rule(ctx, deny, "socket", ScmpArgCmp(0, SCMP_CMP_EQ, family, 0))
        rule(ctx, deny, "socket", ScmpArgCmp(0, SCMP_CMP_GT, top, 0))
    if lib.seccomp_load(ctx) != 0:
        sys.exit("sandbox: loading the memory/address-family filter failed")
    # Filter 2: the system-call allow list; anything else kills the process (SIGSYS), which is
    # stricter than the unit's SystemCallErrorNumber=EPERM and so shows every call outside it.
    ctx = lib.seccomp_init(SCMP_ACT_KILL_PROCESS)
    for name in spec["syscalls"]:
        rule(ctx, SCMP_ACT_ALLOW, name)
    if lib.seccomp_load(ctx) != 0:
        sys.exit("sandbox: loading the system-call filter failed")
    os.execv(argv[0], argv)


class Daemon:
    """photond serve started from an argv; stdout's first line says where it listens."""

    def __init__(self, argv, workdir, spec=None):
        self.log = open(os.path.join(workdir, "daemon.log"), "w+")
        self.workdir = workdir
        prefix = []
        if spec is not None:
            spec_path = os.path.join(workdir, "sandbox.json")
            with open(spec_path, "w") as f:
                json.dump(spec, f)
            prefix = [sys.executable, os.path.abspath(__file__), "--sandbox-exec", spec_path, "--"]
        self.proc = subprocess.Popen(prefix + argv, stdout=subprocess.PIPE, stderr=self.log,
                                     text=True, cwd=workdir)
        self.url = None
        line = ""
        if select.select([self.proc.stdout], [], [], 60)[0]:  # photond may exit or hang instead
            line = self.proc.stdout.readline()
        m = re.match(r"listening on (http://\S+)", line)
        if m:
            self.url = m.group(1).replace("0.0.0.0", "127.0.0.1")

    def stop(self, timeout=30):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait()
            return None
        finally:
            self.proc.stdout.close()
        return code

    def log_tail(self):
        self.log.flush()
        self.log.seek(0)
        return self.log.read()[-1500:]


def http(url, token=None, data=None, timeout=60):
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    if data is not None:
        headers["Content-Type"] = "application/json"
    request = urllib.request.Request(url, data=data, headers=headers, method="POST" if data else "GET")
    try:
        with urllib.request.urlopen(request, timeout=timeout) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def exercise_daemon(where, daemon, token, what):
    """/healthz, /readyz, the token, one small render (Embree under the sandbox), SIGTERM -> 0."""
    if not daemon.url:
        code = daemon.stop(5)
        reason = " (SIGSYS: a system call outside the filter)" if code == -signal.SIGSYS else ""
        problem(where, f"{what}: did not say where it listens (exit {code}{reason}): {daemon.log_tail()}")
        return False
    good = True
    for path, expected in (("/healthz", b"ok"), ("/readyz", b'"ready"')):
        status, body = http(daemon.url + path)
        if status != 200 or expected not in body:
            problem(where, f"{what}: GET {path} answered {status} {body[:200]!r}")
            good = False
    if token:
        status, _ = http(daemon.url + "/v1/jobs")
        if status != 401:
            problem(where, f"{what}: GET /v1/jobs without the token answered {status}, not 401")
            good = False
    job = json.dumps({"scene": {"builtin": "cornell-box-diffuse"}, "preset": "preview",
                      "image": {"width": 32, "height": 32, "tile_size": 16}}).encode()
    status, body = http(daemon.url + "/v1/jobs", token, job)
    if status != 202:
        problem(where, f"{what}: POST /v1/jobs answered {status} {body[:300]!r}")
        good = False
    else:
        job_id = json.loads(body)["id"]
        status, image = http(f"{daemon.url}/v1/jobs/{job_id}/image.exr?wait=true", token, timeout=120)
        if status != 200 or not image.startswith(EXR_MAGIC):
            problem(where, f"{what}: the rendered image answered {status} {image[:200]!r}")
            good = False
    code = daemon.stop()
    if code != 0:
        reason = {-signal.SIGSYS: " (SIGSYS: a system call outside the filter)"}.get(code, "")
        problem(where, f"{what}: SIGTERM ended it with {code}{reason}, not 0: {daemon.log_tail()}")
        good = False
    return good


def run_as_unprivileged(paths):
    """nobody's uid/gid when we are root and nobody can reach the binary; chowns paths to it."""
    if os.geteuid() != 0:
        return None, None
    try:
        import pwd
        entry = pwd.getpwnam("nobody")
    except (ImportError, KeyError):
        return None, None
    for path in paths:
        for root, dirs, files in os.walk(path):
            for name in [root] + [os.path.join(root, n) for n in dirs + files]:
                os.chown(name, entry.pw_uid, entry.pw_gid)
    return entry.pw_uid, entry.pw_gid


def world_executable(path):
    path = os.path.abspath(path)
    while True:
        if not os.stat(path).st_mode & 0o001:
            return False
        parent = os.path.dirname(path)
        if parent == path:
            return True
        path = parent


SELF_TEST = r"""
import mmap, os, socket
try:
    mmap.mmap(-1, 4096, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)
    print("write+execute mapping allowed")
except OSError:
    pass
try:
    socket.socket(socket.AF_NETLINK, socket.SOCK_RAW).close()
    print("AF_NETLINK allowed")
except OSError:
    pass
socket.socket(socket.AF_INET6, socket.SOCK_STREAM).close()
print("reached chroot", flush=True)
os.chroot("/")
"""


def sandbox_self_test(spec):
    """The launcher must refuse what the unit refuses: a writable+executable mapping, a netlink
    socket (EPERM/EAFNOSUPPORT) and chroot (outside @system-service minus @privileged: SIGSYS).
    Python runs under the reference filter, whatever the unit's is."""
    groups = syscall_groups()
    reference = dict(spec, mdwe=True, families=[1, 2, 10], syscalls=sorted(
        expand(groups, ["@system-service"]) - expand(groups, ["@privileged"])))
    with tempfile.TemporaryDirectory(prefix="photond-sandbox.") as tmp:
        spec_path = os.path.join(tmp, "sandbox.json")
        with open(spec_path, "w") as f:
            json.dump(reference, f)
        out = subprocess.run([sys.executable, os.path.abspath(__file__), "--sandbox-exec", spec_path, "--",
                              sys.executable, "-c", SELF_TEST], capture_output=True, text=True, timeout=60)
    if out.returncode != -signal.SIGSYS or out.stdout.strip() != "reached chroot":
        problem(UNIT, f"the seccomp launcher does not enforce the unit's rules: exit {out.returncode}, "
                      f"{out.stdout.strip()!r} {out.stderr.strip()[-300:]!r}")
        return False
    return True


def run_unit_commands(photond, sections, default_argv, dropin_argv):
    if not shutil.which("systemd-analyze"):
        skip("systemd-analyze is not installed: the unit's command line runs without its system-call filter")
        spec = None
    elif libseccomp() is None:
        skip("libseccomp is not installed: the unit's command line runs without its system-call filter")
        spec = None
    else:
        spec = sandbox_spec(sections)
        if not sandbox_self_test(spec):
            spec = None
    binary = os.path.abspath(photond)
    for where, argv, what in ((UNIT, default_argv, "the unit's ExecStart"),
                              (DROPIN, dropin_argv, "the drop-in's ExecStart")):
        if not argv:
            continue
        with tempfile.TemporaryDirectory(prefix="photond-unit-run.") as tmp:
            os.chmod(tmp, 0o711)  # the unprivileged daemon reaches its directories inside
            token = None
            state, creds = os.path.join(tmp, "state"), os.path.join(tmp, "credentials")
            os.makedirs(creds)
            translated = []
            for a in argv:
                a = a.replace("${CREDENTIALS_DIRECTORY}", creds)
                a = re.sub(r"^/usr/local/bin/photond$", binary, a)
                a = re.sub(r"^/var/lib/", state + "/", a)
                translated.append(a)
            listen = flag_value(translated, "--listen")
            if listen:
                host, _ = split_listen(listen)
                translated[translated.index(listen)] = f"[{host}]:0" if ":" in host else f"{host}:0"
            for flag in ("--cache-dir", "--scene-root"):  # StateDirectory= creates them
                value = flag_value(translated, flag)
                if value:
                    os.makedirs(value, exist_ok=True)
            token_file = flag_value(translated, "--token-file")
            if token_file:
                token = "deploy-check-" + os.urandom(8).hex()
                with open(token_file, "w") as f:
                    f.write(token + "\n")
            run_spec = dict(spec) if spec else None
            user = ""
            if run_spec is not None and world_executable(binary):
                uid, gid = run_as_unprivileged([state, creds])
                if uid is not None:
                    run_spec.update(uid=uid, gid=gid)
                    user = " as nobody"
            daemon = Daemon(translated, tmp, run_spec)
            sandbox = " under the unit's seccomp filter" if run_spec else ""
            import resource
            hard = resource.getrlimit(resource.RLIMIT_NOFILE)[1]
            if run_spec and run_spec.get("nofile") and 0 <= hard < run_spec["nofile"]:
                sandbox += f" (LimitNOFILE capped at this machine's hard limit {hard})"
            if exercise_daemon(where, daemon, token, what):
                ok(f"{what} started{user}{sandbox}: /healthz, /readyz"
                   f"{', the token' if token else ''}, a render, SIGTERM -> exit 0")


# --------------------------------------------------------------------------------------------
# Dockerfile

def parse_dockerfile(path):
    """[(INSTRUCTION, arguments)] with continuation lines joined and comments dropped."""
    instructions, pending = [], ""
    for raw in read(path).splitlines():
        stripped = raw.strip()
        if stripped.startswith("#") or (not stripped and not pending):
            continue
        if stripped.endswith("\\"):
            pending += stripped[:-1] + " "
            continue
        line = pending + stripped
        pending = ""
        if line:
            word, _, rest = line.partition(" ")
            instructions.append((word.upper(), rest.strip()))
    return instructions


def makefile_packages():
    text = read(os.path.join(REPO, "Makefile")).replace("\\\n", " ")
    m = re.search(r"^DEBIAN_PACKAGES\s*:?=(.*)$", text, re.M)
    return set(m.group(1).split()) if m else set()


def apt_packages(run_args):
    """Packages that `apt-get install` lines of a RUN name."""
    packages = []
    for command in re.split(r"&&|;|\|\|", run_args):
        words = command.split()
        if words[:2] == ["apt-get", "install"]:
            packages += [w for w in words[2:] if not w.startswith("-")]
    return packages


def needed_packages(binary):
    """Debian packages of the shared libraries the binary names (NEEDED), or None."""
    if not (shutil.which("readelf") and shutil.which("dpkg") and shutil.which("ldd")):
        return None
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]",
                        subprocess.run(["readelf", "-d", binary], capture_output=True, text=True).stdout)
    resolved = dict(re.findall(r"^\s*(\S+) => (\S+)", subprocess.run(["ldd", binary], capture_output=True,
                                                                     text=True).stdout, re.M))
    packages = {}
    for soname in needed:
        path = resolved.get(soname)
        owner = None
        for candidate in filter(None, (path, path and os.path.realpath(path))):
            out = subprocess.run(["dpkg", "-S", candidate], capture_output=True, text=True)
            if out.returncode == 0:
                owner = out.stdout.split(":")[0]
                break
        packages[soname] = owner
    return packages


def dockerignored(relpath, patterns):
    ignored = False
    for pattern in patterns:
        negate = pattern.startswith("!")
        pattern = pattern.lstrip("!").strip("/")
        parts = relpath.split("/")
        prefixes = ["/".join(parts[:i]) for i in range(1, len(parts) + 1)]
        if any(fnmatch.fnmatch(p, pattern) or fnmatch.fnmatch(p, pattern.replace("**/", "")) for p in prefixes):
            ignored = not negate
    return ignored


def check_dockerfile(photond, serve_flags):
    steps = parse_dockerfile(DOCKERFILE)
    good = True
    froms = [a for i, a in steps if i == "FROM"]
    if len(froms) < 2:
        problem(DOCKERFILE, "a multi-stage build (a build stage and a runtime stage) expected")
        good = False
    for arguments in froms:
        image = [w for w in arguments.split() if not w.startswith("--")][0]
        if not re.fullmatch(r"debian:bookworm(-slim)?(@sha256:[0-9a-f]{64})?", image):
            problem(DOCKERFILE, f"FROM {image}: only debian:bookworm images")
            good = False
    stages = []  # [(FROM arguments, [(instruction, arguments)])]
    for instruction, arguments in steps:
        if instruction == "FROM":
            stages.append((arguments, []))
        elif stages:
            stages[-1][1].append((instruction, arguments))
    known_packages = makefile_packages()
    for instruction, arguments in steps:
        if instruction == "ADD" and re.search(r"https?://|git@", arguments):
            problem(DOCKERFILE, f"ADD {arguments}: fetches from outside Debian's archive")
            good = False
        if instruction != "RUN":
            continue
        for url in re.findall(r"(?:https?|ftp)://[^\s\"']+", arguments):
            if not re.match(r"https?://(deb|security)\.debian\.org/", url):
                problem(DOCKERFILE, f"RUN fetches {url}: only Debian's archive (apt-get)")
                good = False
        for tool in ("curl", "wget", "git", "pip", "pip3", "npm", "gem", "go", "cargo", "apt", "dpkg", "snap"):
            if re.search(rf"(^|[\s;&|(]){re.escape(tool)}\s", arguments + " "):
                problem(DOCKERFILE, f"RUN uses {tool}: only apt-get installs are allowed during the build")
                good = False
        for command in re.split(r"&&|;", arguments):
            if "apt-get install" in command and ("-y" not in command.split() or "--no-install-recommends" not in command):
                problem(DOCKERFILE, "apt-get install without -y --no-install-recommends")
                good = False
    if len(stages) >= 2:
        build_packages = [p for _, a in stages[0][1] if _ == "RUN" for p in apt_packages(a)]
        extra = sorted(set(build_packages) - known_packages)
        if extra:
            problem(DOCKERFILE, f"the build stage installs {', '.join(extra)}, not in the Makefile's DEBIAN_PACKAGES")
            good = False
        runtime_packages = {p for i, a in stages[-1][1] if i == "RUN" for p in apt_packages(a)}
        if shutil.which("apt-cache"):  # every package exists in the archive this machine knows
            policy = subprocess.run(["apt-cache", "policy", *sorted(set(build_packages) | runtime_packages)],
                                    capture_output=True, text=True).stdout
            candidates = dict(re.findall(r"^(\S+):\n\s+Installed: .*\n\s+Candidate: (\S+)", policy, re.M))
            if candidates:
                missing = sorted(p for p in set(build_packages) | runtime_packages if candidates.get(p, "(none)") == "(none)")
                if missing:
                    problem(DOCKERFILE, f"no such Debian package (apt-cache policy): {', '.join(missing)}")
                    good = False
        if any(p.endswith("-dev") for p in runtime_packages):
            problem(DOCKERFILE, "the runtime stage installs -dev packages")
            good = False
        binaries = [photond] + [b for b in [os.path.join(os.path.dirname(os.path.abspath(photond)), "..",
                                                         "clients", "photonctl")] if os.path.exists(b)]
        for binary in binaries:
            packages = needed_packages(binary)
            if packages is None:
                skip("readelf, ldd or dpkg missing: the runtime packages are not checked against the binary")
                break
            for soname, owner in sorted(packages.items()):
                if owner is None:
                    problem(DOCKERFILE, f"{os.path.basename(binary)} needs {soname}, which no Debian package installed here provides")
                    good = False
                elif owner not in runtime_packages and owner not in BASE_IMAGE_PACKAGES:
                    problem(DOCKERFILE, f"{os.path.basename(binary)} needs {soname} from {owner}, "
                                        f"which the runtime stage does not install")
                    good = False
        runtime = stages[-1][1]
        if not any(i == "COPY" and "--from=" in a and "photond" in a for i, a in runtime):
            problem(DOCKERFILE, "the runtime stage should COPY --from the build stage the photond binary")
            good = False
    entrypoint = [a for i, a in steps if i == "ENTRYPOINT"]
    argv = None
    if len(entrypoint) != 1:
        problem(DOCKERFILE, "one ENTRYPOINT expected")
        good = False
    else:
        try:
            argv = json.loads(entrypoint[0])
        except ValueError:
            problem(DOCKERFILE, "ENTRYPOINT should be the exec form (a JSON array: photond is PID 1 and gets SIGTERM)")
            good = False
    expose = {int(p.split("/")[0]) for i, a in steps if i == "EXPOSE" for p in a.split()}
    volumes = set()
    for i, a in steps:
        if i == "VOLUME":
            volumes |= set(json.loads(a)) if a.startswith("[") else set(a.split())
    port = None
    if argv:
        if argv[:2] != ["photond", "serve"]:
            problem(DOCKERFILE, f"ENTRYPOINT should start with photond serve, starts {argv[:2]}")
            good = False
        if not check_flags(DOCKERFILE, argv[2:], serve_flags, "serve"):
            good = False
        host, port = split_listen(flag_value(argv, "--listen") or "127.0.0.1:8080")
        if port not in expose:
            problem(DOCKERFILE, f"EXPOSE {sorted(expose)} does not match --listen port {port}")
            good = False
        if host and not is_loopback(host) and not flag_value(argv, "--token-file"):
            problem(DOCKERFILE, "listening beyond loopback needs --token-file")
            good = False
        if flag_value(argv, "--cache-dir") not in volumes:
            problem(DOCKERFILE, f"--cache-dir {flag_value(argv, '--cache-dir')} should be a VOLUME")
            good = False
    user = [a for i, a in steps if i == "USER"]
    if not user or user[-1].split(":")[0] in ("root", "0"):
        problem(DOCKERFILE, "the image should run as a non-root USER")
        good = False
    health = [a for i, a in steps if i == "HEALTHCHECK"]
    if not health or "/healthz" not in health[-1]:
        problem(DOCKERFILE, "a HEALTHCHECK on /healthz expected")
        good = False
    # COPY sources exist and the build context keeps them.
    patterns = [l.strip() for l in read(DOCKERIGNORE).splitlines() if l.strip() and not l.startswith("#")] \
        if os.path.exists(DOCKERIGNORE) else []
    for instruction, arguments in steps:
        if instruction != "COPY" or "--from=" in arguments:
            continue
        sources = [w for w in arguments.split() if not w.startswith("--")][:-1]
        for source in sources:
            if source == ".":
                continue
            if not os.path.exists(os.path.join(REPO, source)):
                problem(DOCKERFILE, f"COPY {source}: no such file in the repository")
                good = False
            elif dockerignored(source, patterns):
                problem(DOCKERIGNORE, f"excludes {source}, which the Dockerfile copies")
                good = False
    for needed in ("CMakeLists.txt", "core/CMakeLists.txt", "server/photond_main.cpp", "clients/photonctl.cpp"):
        if dockerignored(needed, patterns):
            problem(DOCKERIGNORE, f"excludes {needed}, which the build needs")
            good = False
    if shutil.which("shellcheck"):
        out = subprocess.run(["shellcheck", "-f", "gcc", HEALTHCHECK], capture_output=True, text=True)
        if out.returncode != 0:
            problem(HEALTHCHECK, f"shellcheck: {out.stdout.strip()[:600]}")
            good = False
    else:
        skip("shellcheck is not installed (Debian: shellcheck): the shell scripts are not linted")
    if good:
        ok("Dockerfile: debian:bookworm stages, apt-get only, runtime packages cover the binaries' libraries, "
           f"ENTRYPOINT flags, EXPOSE {port}, VOLUME, non-root USER, HEALTHCHECK, build context")
    return argv, port


def run_docker_entrypoint(photond, argv):
    """The ENTRYPOINT with the image's paths moved to a temporary directory, then the health check."""
    binary = os.path.abspath(photond)
    with tempfile.TemporaryDirectory(prefix="photond-image-run.") as tmp:
        translated = [binary if a == "photond" else a for a in argv]
        translated = [tmp + a if a.startswith(("/var/lib/", "/run/", "/srv/")) else a for a in translated]
        listen = flag_value(translated, "--listen")
        host, _ = split_listen(listen)
        translated[translated.index(listen)] = f"{host}:0"
        for flag in ("--cache-dir", "--scene-root"):
            if flag_value(translated, flag):
                os.makedirs(flag_value(translated, flag), exist_ok=True)
        token_file = flag_value(translated, "--token-file")
        missing = subprocess.run(translated, capture_output=True, text=True, timeout=60, cwd=tmp)
        if missing.returncode != 2 or "token" not in missing.stderr:
            problem(DOCKERFILE, f"the ENTRYPOINT without its token file should exit 2 naming it: "
                                f"exit {missing.returncode}, {missing.stderr.strip()[:300]}")
        os.makedirs(os.path.dirname(token_file), exist_ok=True)
        token = "deploy-check-" + os.urandom(8).hex()
        with open(token_file, "w") as f:
            f.write(token + "\n")
        daemon = Daemon(translated, tmp)
        port = int(daemon.url.rsplit(":", 1)[1]) if daemon.url else None
        health_ok = None
        if port:
            live = subprocess.run(["bash", HEALTHCHECK, str(port), "/healthz"], capture_output=True, timeout=30)
            ready = subprocess.run(["bash", HEALTHCHECK, str(port), "/readyz"], capture_output=True, timeout=30)
            missing_route = subprocess.run(["bash", HEALTHCHECK, str(port), "/no-such-route"], capture_output=True,
                                           timeout=30)
            health_ok = (live.returncode, ready.returncode, missing_route.returncode) == (0, 0, 1)
            if not health_ok:
                problem(HEALTHCHECK, f"against a live daemon: /healthz -> {live.returncode}, /readyz -> "
                                     f"{ready.returncode}, a 404 route -> {missing_route.returncode} (0, 0, 1 expected)")
        if exercise_daemon(DOCKERFILE, daemon, token, "the ENTRYPOINT") and health_ok:
            closed = subprocess.run(["bash", HEALTHCHECK, str(port)], capture_output=True, timeout=30)
            if closed.returncode != 1:
                problem(HEALTHCHECK, f"against a stopped daemon it exited {closed.returncode}, not 1")
            else:
                ok("Dockerfile ENTRYPOINT started (paths moved): exit 2 without the token, then /healthz, "
                   "/readyz, the token, a render, SIGTERM -> 0; healthcheck.sh 0 live, 1 on 404 or a closed port")


# --------------------------------------------------------------------------------------------
# Kubernetes

def load_yaml(path):
    try:
        import yaml
    except ImportError:
        problem(path, "PyYAML is not installed (Debian: python3-yaml): the Kubernetes YAML is not checked")
        return None
    with open(path) as f:
        return [d for d in yaml.safe_load_all(f) if d is not None]


def pod_spec(doc):
    if doc.get("kind") in ("Deployment", "Job", "StatefulSet", "DaemonSet"):
        return doc.get("spec", {}).get("template", {}).get("spec", {})
    return None


def script_commands(script):
    """The photond invocations of a shell script: [(subcommand, argv)] (continuations joined)."""
    text = script.replace("\\\n", " ")
    commands = []
    for line in text.splitlines():
        line = line.strip()
        m = re.search(r"(?:^|exec\s+|&&\s*|;\s*)photond\s+(\w+)(.*)$", line)
        if m:
            try:
                argv = shlex.split(m.group(2))
            except ValueError:
                argv = m.group(2).split()
            commands.append((m.group(1), argv))
    return commands


def container_script(container):
    command = (container.get("command") or []) + (container.get("args") or [])
    if command[:2] == ["/bin/sh", "-c"] and len(command) >= 3:
        return command[2]
    return None


def check_pod_security(where, name, spec, container, image_uid):
    pod_ctx, ctx = spec.get("securityContext", {}), container.get("securityContext", {})
    if not (ctx.get("runAsNonRoot", pod_ctx.get("runAsNonRoot"))):
        problem(where, f"{name}: runAsNonRoot: true expected")
    if not ctx.get("readOnlyRootFilesystem"):
        problem(where, f"{name}: readOnlyRootFilesystem: true expected")
    if ctx.get("allowPrivilegeEscalation", True):
        problem(where, f"{name}: allowPrivilegeEscalation: false expected")
    uid = ctx.get("runAsUser", pod_ctx.get("runAsUser"))
    if image_uid is not None and uid is not None and uid != image_uid:
        problem(where, f"{name}: runAsUser {uid} is not the image's USER {image_uid}")
    resources = container.get("resources", {})
    if not resources.get("requests") or not resources.get("limits"):
        problem(where, f"{name}: resources requests and limits expected")


def check_kubernetes(photond, flags, image_argv, image_port, image_uid):
    docs = {}
    for path in (K8S_DAEMON, K8S_REGIONS):
        loaded = load_yaml(path)
        if loaded is None:
            return None
        docs[path] = loaded
        for i, doc in enumerate(loaded):
            missing = [k for k in ("apiVersion", "kind") if not doc.get(k)]
            if not (doc.get("metadata") or {}).get("name"):
                missing.append("metadata.name")
            if missing:
                problem(path, f"document {i + 1}: no {', '.join(missing)}")
    good_before = len(problems)

    # The daemon.
    daemon_docs = docs[K8S_DAEMON]
    deployments = [d for d in daemon_docs if d.get("kind") == "Deployment"]
    services = [d for d in daemon_docs if d.get("kind") == "Service"]
    claims = {d["metadata"]["name"] for path in docs for d in docs[path] if d.get("kind") == "PersistentVolumeClaim"}
    if len(deployments) != 1 or deployments[0]["spec"].get("replicas") != 1:
        problem(K8S_DAEMON, "one Deployment with replicas: 1 expected")
    if len(services) != 1:
        problem(K8S_DAEMON, "one Service expected")
    for deployment in deployments:
        name = deployment["metadata"]["name"]
        spec = pod_spec(deployment)
        containers = spec.get("containers", [])
        if len(containers) != 1:
            problem(K8S_DAEMON, f"{name}: one container expected")
            continue
        container = containers[0]
        ports = {p.get("name"): p["containerPort"] for p in container.get("ports", [])}
        if image_port is not None and image_port not in ports.values():
            problem(K8S_DAEMON, f"{name}: containerPort {sorted(ports.values())} is not the image's --listen port {image_port}")
        for probe, path in (("readinessProbe", "/readyz"), ("livenessProbe", "/healthz")):
            get = (container.get(probe) or {}).get("httpGet") or {}
            port = get.get("port")
            port = ports.get(port, port) if isinstance(port, str) else port
            if get.get("path") != path or port not in ports.values():
                problem(K8S_DAEMON, f"{name}: {probe} should be httpGet {path} on the container port, is {get}")
        args = (container.get("command") or []) + (container.get("args") or [])
        if container.get("command"):
            problem(K8S_DAEMON, f"{name}: command replaces the image's photond serve entrypoint; use args")
        check_flags(K8S_DAEMON, args, flags["serve"], "serve")
        check_pod_security(K8S_DAEMON, name, spec, container, image_uid)
        mounts = {m["mountPath"]: m for m in container.get("volumeMounts", [])}
        volumes = {v["name"]: v for v in spec.get("volumes", [])}
        cache_dir = flag_value(image_argv or [], "--cache-dir") or "/var/lib/photond"
        token_file = flag_value(image_argv or [], "--token-file") or "/run/secrets/photond-token"
        cache = volumes.get((mounts.get(cache_dir) or {}).get("name"), {})
        if not (cache.get("emptyDir") is not None or (cache.get("persistentVolumeClaim") or {}).get("claimName") in claims):
            problem(K8S_DAEMON, f"{name}: {cache_dir} should be a PersistentVolumeClaim of this file or an emptyDir")
        token = mounts.get(token_file)
        secret = volumes.get((token or {}).get("name"), {}).get("secret")
        if not secret:
            problem(K8S_DAEMON, f"{name}: the token Secret should be mounted at {token_file} (the image's --token-file)")
        elif f"kubectl create secret generic {secret['secretName']}" not in read(K8S_DAEMON):
            problem(K8S_DAEMON, f"the header should say how to create the Secret {secret['secretName']}")
        for service in services:
            selector = service["spec"].get("selector", {})
            labels = deployment["spec"]["template"]["metadata"].get("labels", {})
            if any(labels.get(k) != v for k, v in selector.items()):
                problem(K8S_DAEMON, f"Service {service['metadata']['name']}: selector {selector} does not match the pods")
            for p in service["spec"].get("ports", []):
                target = p.get("targetPort", p.get("port"))
                if ports.get(target, target) not in ports.values():
                    problem(K8S_DAEMON, f"Service port {p.get('port')}: targetPort {target} is not a container port")
                if p.get("port") != 8080:
                    problem(K8S_DAEMON, f"the Service should listen on 8080, listens on {p.get('port')}")

    # The render Jobs.
    regions_docs = docs[K8S_REGIONS]
    config_maps = {d["metadata"]["name"]: d for d in regions_docs if d.get("kind") == "ConfigMap"}
    shared_claims = {d["metadata"]["name"]: d for d in regions_docs if d.get("kind") == "PersistentVolumeClaim"}
    jobs = {d["metadata"]["name"]: d for d in regions_docs if d.get("kind") == "Job"}
    steps = {}
    for claim in shared_claims.values():
        if "ReadWriteMany" not in claim["spec"].get("accessModes", []):
            problem(K8S_REGIONS, f"PersistentVolumeClaim {claim['metadata']['name']}: ReadWriteMany expected")
    for name, job in jobs.items():
        spec = pod_spec(job)
        container = spec["containers"][0]
        check_pod_security(K8S_REGIONS, name, spec, container, image_uid)
        script = container_script(container)
        if script is None:
            problem(K8S_REGIONS, f"{name}: command should be [/bin/sh, -c] and the script")
            continue
        commands = script_commands(script)
        if not commands:
            problem(K8S_REGIONS, f"{name}: its script runs no photond command")
        for subcommand, argv in commands:
            if subcommand not in flags:
                problem(K8S_REGIONS, f"{name}: photond has no command {subcommand}")
                continue
            check_flags(K8S_REGIONS, argv, flags[subcommand], subcommand)
        if shutil.which("shellcheck"):
            out = subprocess.run(["shellcheck", "-f", "gcc", "-s", "sh", "-"], input=script, capture_output=True, text=True)
            if out.returncode != 0:
                problem(K8S_REGIONS, f"{name}: shellcheck: {out.stdout.strip()[:600]}")
        mounts = {m["mountPath"]: m["name"] for m in container.get("volumeMounts", [])}
        volumes = {v["name"]: v for v in spec.get("volumes", [])}
        shared = volumes.get(mounts.get("/shared"), {}).get("persistentVolumeClaim", {}).get("claimName")
        if shared not in shared_claims:
            problem(K8S_REGIONS, f"{name}: /shared should be the ReadWriteMany claim of this file")
        if "/config/job.json" in script:
            config = volumes.get(mounts.get("/config"), {}).get("configMap", {}).get("name")
            if config not in config_maps or "job.json" not in config_maps[config].get("data", {}):
                problem(K8S_REGIONS, f"{name}: /config should be the ConfigMap holding job.json")
        for env in container.get("env", []):
            ref = (env.get("valueFrom") or {}).get("configMapKeyRef")
            if ref and ref.get("key") not in config_maps.get(ref.get("name"), {}).get("data", {}):
                problem(K8S_REGIONS, f"{name}: env {env['name']} refers to a ConfigMap key that does not exist")
        if job["spec"].get("completionMode") == "Indexed":
            steps["regions"] = (name, job, script)
        elif any(s == "render" and "--caches-only" in a for s, a in commands):
            steps["prepare"] = (name, job, script)
        elif any(s == "assemble" for s, _ in commands):
            steps["assemble"] = (name, job, script)
    for step in ("prepare", "regions", "assemble"):
        if step not in steps:
            problem(K8S_REGIONS, f"no {step} Job (--caches-only / Indexed region renders / photond assemble)")
    config = next(iter(config_maps.values()), {}).get("data", {})
    if "regions" in steps:
        name, job, script = steps["regions"]
        try:
            image = json.loads(config.get("job.json", "{}")).get("image", {})
            grid = int(config["REGIONS_X"]) * int(config["REGIONS_Y"])
            if (str(image.get("width")), str(image.get("height"))) != (config.get("WIDTH"), config.get("HEIGHT")):
                problem(K8S_REGIONS, f"WIDTH/HEIGHT {config.get('WIDTH')}x{config.get('HEIGHT')} are not job.json's "
                                     f"image size {image.get('width')}x{image.get('height')}")
            if job["spec"].get("completions") != grid:
                problem(K8S_REGIONS, f"{name}: completions {job['spec'].get('completions')} is not "
                                     f"REGIONS_X * REGIONS_Y = {grid}")
        except (KeyError, ValueError) as e:
            problem(K8S_REGIONS, f"the ConfigMap should hold job.json, WIDTH, HEIGHT, REGIONS_X, REGIONS_Y ({e})")
        if "JOB_COMPLETION_INDEX" not in script or "image.region=" not in script:
            problem(K8S_REGIONS, f"{name}: the script should render region JOB_COMPLETION_INDEX with --set image.region=")
    if len(problems) == good_before:
        ok("Kubernetes: documents named, probes /readyz and /healthz on the container port, Service, token Secret, "
           "security contexts, Job scripts' photond flags, ConfigMap/grid consistency, ReadWriteMany /shared")
    return steps, config


def run_render_steps(photond, steps, config):
    """The three Jobs' scripts with /shared and /config in a temporary directory."""
    if not all(s in steps for s in ("prepare", "regions", "assemble")):
        return
    binary = os.path.abspath(photond)
    with tempfile.TemporaryDirectory(prefix="photond-k8s-run.") as tmp:
        os.makedirs(os.path.join(tmp, "bin"))
        os.makedirs(os.path.join(tmp, "config"))
        os.symlink(binary, os.path.join(tmp, "bin", "photond"))
        with open(os.path.join(tmp, "config", "job.json"), "w") as f:
            f.write(config["job.json"])
        env = dict(os.environ, PATH=os.path.join(tmp, "bin") + os.pathsep + os.environ.get("PATH", ""),
                   **{k: v for k, v in config.items() if k != "job.json"})

        def run(step, extra_env=None):
            script = steps[step][2].replace("/shared", tmp + "/shared").replace("/config", tmp + "/config")
            return subprocess.run(["/bin/sh", "-c", script], env=dict(env, **(extra_env or {})),
                                  capture_output=True, text=True, timeout=600)

        out = run("prepare")
        if out.returncode != 0:
            problem(K8S_REGIONS, f"the prepare script exited {out.returncode}: {out.stderr[-800:]}")
            return
        count = steps["regions"][1]["spec"]["completions"]
        for i in range(count):
            out = run("regions", {"JOB_COMPLETION_INDEX": str(i)})
            if out.returncode != 0:
                problem(K8S_REGIONS, f"the region script, index {i}, exited {out.returncode}: {out.stderr[-800:]}")
                return
        outside = run("regions", {"JOB_COMPLETION_INDEX": str(count)})
        if outside.returncode != 2:
            problem(K8S_REGIONS, f"the region script with index {count} (outside the grid) exited "
                                 f"{outside.returncode}, not 2 (which fails the Job at once)")
        out = run("assemble")
        if out.returncode != 0:
            problem(K8S_REGIONS, f"the assemble script exited {out.returncode}: {out.stderr[-800:]}")
            return
        frames = [os.path.join(root, f) for root, _, files in os.walk(os.path.join(tmp, "shared", "frames"))
                  for f in files if f.endswith(".exr")]
        whole = os.path.join(tmp, "whole.exr")
        out = subprocess.run([binary, "render", "--job", os.path.join(tmp, "config", "job.json"), "-o", whole,
                              "--quiet"], capture_output=True, text=True, timeout=600)
        if out.returncode != 0 or len(frames) != 1:
            problem(K8S_REGIONS, f"expected one assembled frame ({frames}) and a whole render (exit {out.returncode})")
            return
        with open(frames[0], "rb") as a, open(whole, "rb") as b:
            identical = a.read() == b.read()
        if not identical:
            problem(K8S_REGIONS, "the assembled frame differs from `photond render` of the whole view")
            return
        hits = []
        for i in range(count):
            with open(os.path.join(tmp, "shared", "parts", f"part-{i}.json")) as f:
                stats = json.load(f)
            hits.append(all((stats.get(k) or {}).get("cache") == "hit" for k in ("photons", "irradiance_cache")))
        if not all(hits):
            problem(K8S_REGIONS, "a region did not take the prepared caches (its statistics say miss)")
            return
        ok(f"render-regions.yaml run as scripts: prepare, {count} regions (index {count} refused with 2), "
           "assemble; frame byte-identical to the whole render; every region hit the prepared caches")


# --------------------------------------------------------------------------------------------
# farms.md

def check_farms(flags):
    text = read(FARMS)
    before = len(problems)
    for needed in ("Flamenco", "OpenCue", "Deadline", "--caches-only", "--cache-dir", "image.region",
                   "photond assemble", "photonctl", "/v1/jobs/ID/image.exr", "Idempotency-Key", "atomic"):
        if needed not in text:
            problem(FARMS, f"should mention {needed}")
    for code, meaning in (("0", "done"), ("1", "failure"), ("2", "bad arguments")):
        if not re.search(rf"^\|\s*{code}\s*\|[^\n]*{meaning}", text, re.M):
            problem(FARMS, f"the exit-code table should give {code} ({meaning})")
    # Shell examples: indented lines that start with `photond`, continuations joined.
    joined = re.sub(r"\\\n\s*", " ", text)
    for line in joined.splitlines():
        m = re.match(r"\s{4,}photond\s+(\w+)(.*)$", line)
        if not m:
            continue
        subcommand, rest = m.group(1), m.group(2)
        if subcommand not in flags:
            problem(FARMS, f"photond has no command {subcommand}")
            continue
        try:
            argv = shlex.split(rest)
        except ValueError:
            argv = rest.split()
        check_flags(FARMS, argv, flags[subcommand], subcommand)
    if len(problems) == before:
        ok("farms.md: Flamenco, OpenCue, Deadline, the three steps, results, exit codes 0/1/2, retries; "
           "its photond command lines use existing flags")


# --------------------------------------------------------------------------------------------

def main(args):
    if args[:1] == ["--sandbox-exec"]:
        sandbox_exec(args[1], args[3:])  # args[2] is "--"
        return 1
    static = "--static" in args
    args = [a for a in args if a != "--static"]
    if len(args) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    photond = args[0]
    if not os.access(photond, os.X_OK):
        print(f"check_deploy: {photond} is not an executable (build it first)", file=sys.stderr)
        return 2
    flags = {c: help_flags(photond, c) for c in ("serve", "render", "assemble")}

    sections, default_argv, dropin_argv = check_unit_static(photond, flags["serve"])
    systemd_analyze(photond)
    image_argv, image_port = check_dockerfile(photond, flags["serve"])
    user = [a for i, a in parse_dockerfile(DOCKERFILE) if i == "USER"]
    image_uid = int(user[-1].split(":")[0]) if user and user[-1].split(":")[0].isdigit() else None
    kube = check_kubernetes(photond, flags, image_argv, image_port, image_uid)
    check_farms(flags)
    if static:
        skip("--static: nothing started")
    else:
        run_unit_commands(photond, sections, default_argv, dropin_argv)
        if image_argv:
            run_docker_entrypoint(photond, image_argv)
        if kube:
            run_render_steps(photond, *kube)
    if problems:
        print(f"\ncheck_deploy: {len(problems)} problem(s):", file=sys.stderr)
        for p in problems:
            print(f"  {p}", file=sys.stderr)
        return 1
    print("check_deploy: deploy/ is consistent with", photond)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
