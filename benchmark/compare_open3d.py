#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""compare_open3d.py: our orientation program against CGAL and Open3D, on the same files.

For each cloud it runs three programs, each as its own process on the very same input file:

- ours:   ``<build>/examples/orient_normals --quiet [--ours-args] IN OUT.xyz`` (our defaults);
- CGAL:   ``<build>/benchmark/cgal_mst_orient --quiet --k K IN OUT.xyz``
          (``CGAL::mst_orient_normals``, K = 18 by default, CGAL's documented value);
- Open3D: this script in worker mode (``--open3d-worker IN OUT.ply K``) under a Python that has
          ``open3d`` (Debian 12: ``apt-get install python3-open3d``, i.e. ``/usr/bin/python3``):
          ``o3d.io.read_point_cloud`` -> ``orient_normals_consistent_tangent_plane(K)`` ->
          ``o3d.io.write_point_cloud`` (binary PLY).  K = 18 as for CGAL; Open3D documents
          no default or recommended value (its surface-reconstruction tutorial uses 100 on a
          5,000-point cloud: ``--open3d-k 100``).

Each process is run under ``/usr/bin/time -v``: the time is the wall clock of the whole process
(start-up, read, orient, write; for Open3D this includes the Python interpreter and the
``import open3d``, also reported separately), the memory is the peak RSS ("Maximum resident
set size"); with ``--repeat R`` the fastest time and the largest peak are kept.  A run that exceeds ``--timeout`` seconds or ``--max-mb`` MB of RSS (checked every
0.2 s over the process tree) is killed and recorded as such; Open3D is not started at all on
clouds larger than ``--open3d-max-points``.

Clouds are made as ``compare_cgal`` makes them, by ``<build>/benchmark/make_cloud MESH N PREFIX
--noise F --seed S`` (area-uniform samples, PCA normals with k = 18, random signs; ``PREFIX.xyz``
and ``PREFIX.gt.xyz``), or given with ``--cloud MESH.off CLOUD.xyz`` (``x y z nx ny nz`` lines: the
CGAL wrapper reads xyz only).

Wrong normals are counted by ``<build>/benchmark/count_wrong_normals MESH OUT --json``: a normal is
wrong when its dot product with the outward normal of the closest mesh triangle is <= 0.  When the
``PREFIX.gt.xyz`` truth exists and the checking Python has numpy/open3d, every output is also
checked point by point: same number of points, same order and positions as the input, no zero or
non-finite normal ("missing"), and wrong normals against the sampling truth (``compare_cgal``'s
measure).  A crash, a kill, a missing output or missing normals are recorded in the table; the
script goes on with the next cloud.

Output: a Markdown report on stdout (settings, one row per cloud, a totals row over the clouds where
all three succeeded, then the per-point check); progress on stderr.  Exit status 0 when every run
succeeded, 1 when a run failed, 2 on usage errors.

Examples (from the repository root, after building make_cloud, count_wrong_normals,
cgal_mst_orient and orient_normals)::

    /usr/bin/python3 benchmark/compare_open3d.py --build build                  # 8 meshes, 30k, noise 0,0.005
    /usr/bin/python3 benchmark/compare_open3d.py --build build --points 1000000 --noise 0 \\
        --meshes ../shared/data/meshes/bunny00.off
"""

import argparse
import glob
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

DEFAULT_MESH_DIR = os.path.normpath(
    os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "meshes"))


# ----------------------------------------------------------------------------------------------
# Worker modes (run under a Python that has open3d)
# ----------------------------------------------------------------------------------------------

def open3d_format(path):
    """Open3D's format name for a cloud file with normals."""
    ext = os.path.splitext(path)[1].lower()
    return "xyzn" if ext in (".xyz", ".pwn", ".xyzn") else "auto"


def open3d_worker(input_path, output_path, k):
    """Reads, orients with Open3D, writes; prints one JSON line with the stage times."""
    t0 = time.perf_counter()
    import numpy as np
    import open3d as o3d
    t_import = time.perf_counter() - t0
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    t = time.perf_counter()
    cloud = o3d.io.read_point_cloud(input_path, format=open3d_format(input_path))
    t_read = time.perf_counter() - t
    n = len(cloud.points)
    if n == 0 or not cloud.has_normals():
        print("open3d_worker: read no points or no normals from %s" % input_path, file=sys.stderr)
        return 1

    t = time.perf_counter()
    cloud.orient_normals_consistent_tangent_plane(k)
    t_orient = time.perf_counter() - t

    normals = np.asarray(cloud.normals)
    length = np.linalg.norm(normals, axis=1) if len(normals) else np.zeros(0)
    missing = int(n - len(normals)) + int(np.count_nonzero(~np.isfinite(length) | (length == 0)))

    t = time.perf_counter()
    if not o3d.io.write_point_cloud(output_path, cloud, write_ascii=False):
        print("open3d_worker: cannot write %s" % output_path, file=sys.stderr)
        return 1
    t_write = time.perf_counter() - t
    print(json.dumps({"points": n, "normals": len(normals), "missing_normals": missing,
                      "seconds": {"import": t_import, "read": t_read, "orient": t_orient,
                                  "write": t_write}}))
    return 0


def read_cloud_arrays(path):
    """Points and normals of a cloud file, as numpy arrays (needs open3d for PLY)."""
    import numpy as np
    if open3d_format(path) == "xyzn":
        data = np.loadtxt(path, dtype=np.float64, ndmin=2)
        if data.shape[1] < 6:
            return data[:, :3], np.zeros((len(data), 3))
        return data[:, :3], data[:, 3:6]
    import open3d as o3d
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    cloud = o3d.io.read_point_cloud(path)
    points = np.asarray(cloud.points)
    normals = np.asarray(cloud.normals) if cloud.has_normals() else np.zeros((0, 3))
    return points, normals


def check_worker(input_path, truth_path, output_paths):
    """Per-point check of outputs against the input and the sampling truth; one JSON line."""
    import numpy as np
    points, _ = read_cloud_arrays(input_path)
    truth = np.loadtxt(truth_path, dtype=np.float64, ndmin=2)
    gt_normals = truth[:, 3:6]
    scale = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 1.0
    report = {}
    for path in output_paths:
        entry = {}
        try:
            out_points, out_normals = read_cloud_arrays(path)
        except Exception as error:  # an unreadable output is a result, not a crash of the check
            report[path] = {"error": str(error).splitlines()[0] if str(error) else repr(error)}
            continue
        entry["points"] = int(len(out_points))
        same_count = len(out_points) == len(points) and len(out_normals) == len(points)
        entry["same_order"] = bool(same_count and np.all(
            np.abs(out_points - points) <= 1e-5 * scale))
        if len(out_normals) == len(out_points):
            length = np.linalg.norm(out_normals, axis=1)
            entry["missing_normals"] = int(np.count_nonzero(~np.isfinite(length) | (length == 0)))
        else:
            entry["missing_normals"] = int(len(out_points))
        if entry["same_order"]:
            dots = np.einsum("ij,ij->i", out_normals, gt_normals)
            entry["wrong_truth"] = int(np.count_nonzero(~(dots > 0)))  # <= 0 or NaN
        report[path] = entry
    print(json.dumps(report))
    return 0


# ----------------------------------------------------------------------------------------------
# Running programs
# ----------------------------------------------------------------------------------------------

def process_tree_rss_kb(pid):
    """Sum of VmRSS (KiB) over `pid` and its descendants (Linux /proc)."""
    total = 0
    stack = [pid]
    seen = set()
    while stack:
        p = stack.pop()
        if p in seen:
            continue
        seen.add(p)
        try:
            with open("/proc/%d/status" % p) as status:
                for line in status:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1])
                        break
            for task in os.listdir("/proc/%d/task" % p):
                with open("/proc/%d/task/%s/children" % (p, task)) as children:
                    stack.extend(int(c) for c in children.read().split())
        except (OSError, ValueError):
            continue
    return total


def run_measured(command, log_prefix, timeout, max_mb):
    """Runs `command` under /usr/bin/time -v; returns a dict with seconds, peak_mb, status."""
    time_path = log_prefix + ".time"
    stdout_path = log_prefix + ".stdout"
    stderr_path = log_prefix + ".stderr"
    result = {"ok": False, "seconds": None, "peak_mb": None, "reason": ""}
    with open(os.devnull, "rb") as devnull, open(stdout_path, "wb") as out, open(stderr_path, "wb") as err:
        start = time.monotonic()
        try:
            child = subprocess.Popen(["/usr/bin/time", "-v", "-o", time_path] + command, stdin=devnull,
                                     stdout=out, stderr=err, start_new_session=True)
        except OSError as error:
            result["reason"] = "cannot start: %s" % error
            return result
        # A watcher thread enforces the limits; this thread waits, so the time is exact.
        state = {"killed": "", "peak_polled_kb": 0}
        finished = threading.Event()

        def watch():
            while not finished.wait(0.2):
                elapsed = time.monotonic() - start
                rss_kb = process_tree_rss_kb(child.pid)
                state["peak_polled_kb"] = max(state["peak_polled_kb"], rss_kb)
                if timeout and elapsed > timeout:
                    state["killed"] = "killed after %.0f s (limit %g s)" % (elapsed, timeout)
                elif max_mb and rss_kb > max_mb * 1024:
                    state["killed"] = "killed at %.0f MB RSS (limit %g MB)" % (rss_kb / 1024.0, max_mb)
                if state["killed"]:
                    kill_group(child)
                    return

        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        try:
            child.wait()
            result["seconds"] = time.monotonic() - start
        except BaseException:  # interrupted: do not leave the measured program running
            kill_group(child)
            child.wait()
            raise
        finally:
            finished.set()
            watcher.join()
        killed = state["killed"]
        peak_polled_kb = state["peak_polled_kb"]
    # What /usr/bin/time reports about the measured program.
    timing = ""
    try:
        with open(time_path) as f:
            timing = f.read()
    except OSError:
        pass
    match = re.search(r"Maximum resident set size \(kbytes\): (\d+)", timing)
    if match:
        result["peak_mb"] = int(match.group(1)) / 1024.0
    elif peak_polled_kb:
        result["peak_mb"] = peak_polled_kb / 1024.0
    exit_match = re.search(r"Exit status: (\d+)", timing)
    signal_match = re.search(r"Command terminated by signal (\d+)", timing)
    if killed:
        result["reason"] = killed
    elif signal_match:
        number = int(signal_match.group(1))
        try:
            name = signal.Signals(number).name
        except ValueError:
            name = "signal %d" % number
        result["reason"] = "crashed (%s)" % name
    elif exit_match and int(exit_match.group(1)) != 0:
        result["reason"] = "exit status %s" % exit_match.group(1)
    elif child.returncode != 0:
        result["reason"] = "exit status %d" % child.returncode
    else:
        result["ok"] = True
    if not result["ok"]:
        try:
            with open(stderr_path, errors="replace") as f:
                lines = [line.strip() for line in f.readlines() if line.strip()]
            # An exception's message (e.g. Open3D's "RuntimeError: QH6239 Qhull precision error: ...")
            # says more than the last lines, which may be a dump of qhull's options.
            errors = [line for line in lines if re.match(r"^\w*(Error|Exception)\b", line)]
            tail = errors[-1:] if errors else lines[-3:]
            result["stderr_tail"] = [line if len(line) <= 160 else line[:157] + "..." for line in tail]
        except OSError:
            pass
    return result


def kill_group(child):
    """Kills the process group of `child` (started with its own session by run_measured)."""
    try:
        os.killpg(child.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def open3d_stages(stdout_path):
    """The JSON line printed by the Open3D worker (stage times, missing normals), or None."""
    try:
        with open(stdout_path) as f:
            return json.loads(f.read().strip().splitlines()[-1])
    except (OSError, ValueError, IndexError):
        return None


def count_wrong(count_program, mesh, cloud):
    """Runs count_wrong_normals MESH CLOUD --json; returns its JSON object or None."""
    try:
        done = subprocess.run([count_program, mesh, cloud, "--json"], stdin=subprocess.DEVNULL,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False)
    except OSError:
        return None
    if done.returncode != 0:
        return None
    try:
        return json.loads(done.stdout.decode().strip().splitlines()[-1])
    except (ValueError, IndexError):
        return None


# ----------------------------------------------------------------------------------------------
# Driver
# ----------------------------------------------------------------------------------------------

SIDES = ("ours", "cgal", "open3d")
SIDE_TITLES = {"ours": "ours", "cgal": "CGAL", "open3d": "Open3D"}


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        prog="compare_open3d.py",
        description="Ours, CGAL::mst_orient_normals and Open3D's orient_normals_consistent_tangent_plane "
                    "on the same clouds; prints a Markdown table (see the module docstring).")
    parser.add_argument("--build", default="build", help="build directory (default: build)")
    parser.add_argument("--meshes", nargs="+", default=None,
                        help="meshes (.off files or directories of them; default: %s)" % DEFAULT_MESH_DIR)
    parser.add_argument("--points", type=int, default=30000, help="points per cloud (default 30000)")
    parser.add_argument("--noise", default="0,0.005", help="noise levels, x bbox diagonal (default 0,0.005)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the clouds (default 1)")
    parser.add_argument("--cloud", nargs=2, action="append", metavar=("MESH", "CLOUD"), default=[],
                        help="an existing .xyz cloud with normals and its mesh (repeatable; replaces the generated clouds)")
    parser.add_argument("--k", type=int, default=18, help="k of CGAL (default 18)")
    parser.add_argument("--open3d-k", type=int, default=None, help="k of Open3D (default: --k)")
    parser.add_argument("--ours-args", default="", help="extra arguments for ours")
    parser.add_argument("--ours", default=None, help="our program (default BUILD/examples/orient_normals)")
    parser.add_argument("--cgal", default=None, help="CGAL peer (default BUILD/benchmark/cgal_mst_orient)")
    parser.add_argument("--python", default=None,
                        help="Python with open3d for the Open3D runs (default: this one if it has open3d, "
                             "else /usr/bin/python3)")
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="kill a run after this many seconds (default 900; 0: no limit)")
    parser.add_argument("--max-mb", type=float, default=8192.0,
                        help="kill a run whose RSS exceeds this many MB (default 8192; 0: no limit)")
    parser.add_argument("--open3d-max-points", type=int, default=0,
                        help="do not run Open3D on clouds with more points (default 0: no limit)")
    parser.add_argument("--no-open3d", action="store_true", help="leave Open3D out")
    parser.add_argument("--no-check", action="store_true", help="skip the per-point check against the truth")
    parser.add_argument("--repeat", type=int, default=1,
                        help="run each program R times per cloud; report the fastest time and the largest "
                             "peak (default 1)")
    parser.add_argument("--keep", default=None, help="keep clouds, outputs and logs in this directory")
    parser.add_argument("--open3d-worker", nargs=3, metavar=("IN", "OUT", "K"), help=argparse.SUPPRESS)
    parser.add_argument("--check-worker", nargs="+", metavar="FILE", help=argparse.SUPPRESS)
    options = parser.parse_args(argv)
    try:
        options.noise_levels = [float(x) for x in options.noise.split(",")]
    except ValueError:
        parser.error("invalid --noise '%s'" % options.noise)
    if options.points < 1 or options.k < 2 or options.repeat < 1:
        parser.error("--points and --repeat must be >= 1 and --k >= 2")
    if options.open3d_k is None:
        options.open3d_k = options.k
    return options


def collect_meshes(arguments):
    inputs = arguments or [DEFAULT_MESH_DIR]
    meshes = []
    for item in inputs:
        if os.path.isdir(item):
            found = sorted(glob.glob(os.path.join(item, "*.off")))
            if not found:
                raise SystemExit("compare_open3d.py: no .off file in '%s'" % item)
            meshes.extend(found)
        elif os.path.isfile(item):
            meshes.append(item)
        else:
            raise SystemExit("compare_open3d.py: no mesh file or directory '%s'" % item)
    return meshes


def python_with_open3d(requested):
    """The Python interpreter to run Open3D with, or None if none has open3d."""
    candidates = [requested] if requested else [sys.executable, "/usr/bin/python3"]
    for python in candidates:
        if python and os.path.exists(python) and subprocess.run(
                [python, "-c", "import open3d"], stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL).returncode == 0:
            return python
    return None


def fmt(value, digits=2):
    return "-" if value is None else "%.*f" % (digits, value)


def side_cells(side):
    """seconds, MB and wrong cells of one program on one cloud."""
    if side is None:
        return ["-", "-", "not run"]
    if side.get("skipped"):
        return ["-", "-", side.get("reason", "skipped")]
    if not side.get("ok"):
        return [fmt(side.get("seconds")), fmt(side.get("peak_mb"), 1), "**FAILED**: " + side.get("reason", "")]
    wrong = side["wrong"]
    text = "%d (%.3f%%)" % (wrong["wrong"], wrong["wrong_percent"])
    if side.get("missing"):
        text += ", %d missing" % side["missing"]
    return [fmt(side["seconds"]), fmt(side["peak_mb"], 1), text]


def ratio(a, b):
    if a is None or b is None or b <= 0:
        return "-"
    return "%.2fx" % (a / b)


def main(argv):
    options = parse_arguments(argv)
    # SIGTERM unwinds like Ctrl-C: the measured program is killed and the work directory removed.
    signal.signal(signal.SIGTERM, lambda number, frame: sys.exit(128 + number))
    if options.open3d_worker:
        source, target, k = options.open3d_worker
        return open3d_worker(source, target, int(k))
    if options.check_worker:
        if len(options.check_worker) < 3:
            return 2
        return check_worker(options.check_worker[0], options.check_worker[1], options.check_worker[2:])

    build = os.path.abspath(options.build)
    ours = options.ours or os.path.join(build, "examples", "orient_normals")
    cgal = options.cgal or os.path.join(build, "benchmark", "cgal_mst_orient")
    make_cloud = os.path.join(build, "benchmark", "make_cloud")
    counter = os.path.join(build, "benchmark", "count_wrong_normals")
    needed = [ours, cgal, counter] + ([] if options.cloud else [make_cloud])
    for program in needed:
        if not os.access(program, os.X_OK):
            print("compare_open3d.py: missing program %s (build it: cmake --build %s --target make_cloud "
                  "count_wrong_normals cgal_mst_orient orient_normals)" % (program, options.build), file=sys.stderr)
            return 2
    if not os.access("/usr/bin/time", os.X_OK):
        print("compare_open3d.py: /usr/bin/time is needed (apt-get install time)", file=sys.stderr)
        return 2
    python = None
    if not options.no_open3d:
        python = python_with_open3d(options.python)
        if python is None:
            print("compare_open3d.py: no Python with open3d (Debian: apt-get install python3-open3d, then run "
                  "with /usr/bin/python3 or pass --python); use --no-open3d to leave it out", file=sys.stderr)
            return 2
    checker = None if options.no_check else python_with_open3d(options.python)

    work = options.keep or tempfile.mkdtemp(prefix="compare_open3d_")
    os.makedirs(work, exist_ok=True)
    script = os.path.abspath(__file__)

    # The clouds: (mesh, noise label, cloud path, truth path or None).
    clouds = []
    if options.cloud:
        for mesh, cloud in options.cloud:
            clouds.append((mesh, "given", os.path.abspath(cloud), None))
    else:
        for mesh in collect_meshes(options.meshes):
            for noise in options.noise_levels:
                clouds.append((mesh, noise, None, None))

    rows = []
    any_failed = False
    try:
        for index, (mesh, noise, cloud, truth) in enumerate(clouds, 1):
            name = os.path.splitext(os.path.basename(mesh))[0]
            if cloud is None:
                prefix = os.path.join(work, "%s_%d_noise%g_seed%d" % (name, options.points, noise, options.seed))
                print("[%d/%d] %s, %d points, noise %g: cloud" % (index, len(clouds), name, options.points, noise),
                      end="", file=sys.stderr, flush=True)
                done = subprocess.run([make_cloud, mesh, str(options.points), prefix, "--noise", repr(noise),
                                       "--seed", str(options.seed)], stdin=subprocess.DEVNULL,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
                if done.returncode != 0:
                    print("\ncompare_open3d.py: make_cloud failed: %s" % done.stderr.decode().strip(), file=sys.stderr)
                    any_failed = True
                    continue
                cloud, truth = prefix + ".xyz", prefix + ".gt.xyz"
            else:
                prefix = os.path.join(work, os.path.splitext(os.path.basename(cloud))[0])
                print("[%d/%d] %s (%s):" % (index, len(clouds), name, cloud), end="", file=sys.stderr, flush=True)
            npoints = options.points if truth else None

            outputs = {"ours": prefix + ".ours.xyz", "cgal": prefix + ".cgal.xyz", "open3d": prefix + ".open3d.ply"}
            commands = {
                "ours": [ours, "--quiet"] + options.ours_args.split() + [cloud, outputs["ours"]],
                "cgal": [cgal, "--quiet", "--k", str(options.k), cloud, outputs["cgal"]],
            }
            if python:
                commands["open3d"] = [python, script, "--open3d-worker", cloud, outputs["open3d"],
                                      str(options.open3d_k)]
            row = {"mesh": name, "noise": noise, "points": npoints, "sides": {}}
            for key in SIDES:
                if key not in commands:
                    continue
                if key == "open3d" and options.open3d_max_points and npoints and npoints > options.open3d_max_points:
                    row["sides"][key] = {"ok": False, "skipped": True, "seconds": None, "peak_mb": None,
                                         "reason": "skipped (more than %d points)" % options.open3d_max_points}
                    print(", open3d skipped", end="", file=sys.stderr, flush=True)
                    continue
                print(", %s" % key, end="", file=sys.stderr, flush=True)
                if os.path.exists(outputs[key]):
                    os.remove(outputs[key])
                side = None
                for _ in range(options.repeat):
                    run = run_measured(commands[key], prefix + "." + key, options.timeout, options.max_mb)
                    if key == "open3d" and run["ok"]:
                        run["stages"] = open3d_stages(prefix + ".open3d.stdout")
                    peak = max(run["peak_mb"] or 0.0, (side or {}).get("peak_mb") or 0.0)
                    if side is None or not run["ok"] or run["seconds"] < side["seconds"]:
                        side = dict(run)  # the fastest run (its stages too), or the failure
                    side["peak_mb"] = peak if peak > 0 else None
                    if not run["ok"]:
                        break
                if side["ok"] and not os.path.exists(outputs[key]):
                    side.update(ok=False, reason="no output file")
                if side["ok"]:
                    wrong = count_wrong(counter, mesh, outputs[key])
                    if wrong is None:
                        missing = (side.get("stages") or {}).get("missing_normals")
                        side.update(ok=False, reason=("%d missing (zero or non-finite) normals, " % missing
                                                      if missing else "") + "output not readable by count_wrong_normals")
                    else:
                        side["wrong"] = wrong
                        if row["points"] is None:
                            row["points"] = wrong["points"]
                if key == "open3d" and side["ok"] and side.get("stages"):
                    side["missing"] = side["stages"].get("missing_normals", 0)
                print(" %s s" % fmt(side["seconds"]), end="", file=sys.stderr, flush=True)
                row["sides"][key] = side
            # Per-point check (order, count, missing normals, wrong against the sampling truth).
            if checker and truth:
                paths = [outputs[k] for k in SIDES if row["sides"].get(k, {}).get("ok")]
                if paths:
                    done = subprocess.run([checker, script, "--check-worker", cloud, truth] + paths,
                                          stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
                    try:
                        report = json.loads(done.stdout.decode().strip().splitlines()[-1])
                    except (ValueError, IndexError):
                        report = {}
                    for key in SIDES:
                        entry = report.get(outputs[key])
                        if entry is None:
                            continue
                        side = row["sides"][key]
                        side["check"] = entry
                        if entry.get("missing_normals"):
                            side["missing"] = entry["missing_normals"]
                        if npoints is not None and entry.get("points") != npoints:
                            side.update(ok=False, reason="wrote %s of %d points" % (entry.get("points"), npoints))
            for side in row["sides"].values():
                if not side.get("ok") and not side.get("skipped"):
                    any_failed = True
            print("", file=sys.stderr)
            rows.append(row)
    finally:
        if not options.keep:
            shutil.rmtree(work, ignore_errors=True)

    print_report(options, rows, python)
    return 1 if any_failed else 0


def print_report(options, rows, python):
    sides = [s for s in SIDES if s != "open3d" or python]
    print("Settings: points %s, noise %s, seed %d; CGAL k = %d; Open3D k = %d; ours: defaults%s; %d run(s) "
          "per program and cloud (fastest time, largest peak). "
          "Whole process (read, orient, write) under /usr/bin/time -v; MB = peak RSS; wrong = "
          "count_wrong_normals against the mesh (dot with the closest triangle's outward normal <= 0)."
          % ("given" if options.cloud else options.points, "given" if options.cloud else options.noise,
             options.seed, options.k, options.open3d_k,
             (" + '%s'" % options.ours_args) if options.ours_args else "", options.repeat))
    print()
    header = ["mesh", "points", "noise"]
    for s in sides:
        header += ["%s s" % SIDE_TITLES[s], "%s MB" % SIDE_TITLES[s], "%s wrong" % SIDE_TITLES[s]]
    if python:
        header += ["Open3D orient s"]
    header += ["CGAL/ours time", "CGAL/ours mem"]
    if python:
        header += ["Open3D/ours time", "Open3D/ours mem"]
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join([":---", "---:", "---:"] + ["---:"] * (len(header) - 3)) + "|")
    totals = {s: {"seconds": 0.0, "peak_mb": 0.0, "wrong": 0} for s in sides}
    # Totals cover the programs that were run on every cloud (not skipped), over the clouds where
    # all of them succeeded.
    summed = [s for s in sides if not any(row["sides"].get(s, {}).get("skipped") for row in rows)]
    total_points = 0
    complete = 0
    for row in rows:
        cells = [row["mesh"], str(row["points"] or "-"), str(row["noise"])]
        for s in sides:
            cells += side_cells(row["sides"].get(s))
        get = lambda s, field: row["sides"].get(s, {}).get(field) if row["sides"].get(s, {}).get("ok") else None
        if python:
            stages = row["sides"].get("open3d", {}).get("stages") if get("open3d", "ok") else None
            cells.append(fmt(stages["seconds"]["orient"]) if stages else "-")
        cells += [ratio(get("cgal", "seconds"), get("ours", "seconds")),
                  ratio(get("cgal", "peak_mb"), get("ours", "peak_mb"))]
        if python:
            cells += [ratio(get("open3d", "seconds"), get("ours", "seconds")),
                      ratio(get("open3d", "peak_mb"), get("ours", "peak_mb"))]
        print("| " + " | ".join(cells) + " |")
        if all(get(s, "ok") for s in summed):
            complete += 1
            total_points += row["points"] or 0
            for s in summed:
                totals[s]["seconds"] += row["sides"][s]["seconds"]
                totals[s]["peak_mb"] = max(totals[s]["peak_mb"], row["sides"][s]["peak_mb"] or 0.0)
                totals[s]["wrong"] += row["sides"][s]["wrong"]["wrong"]
    if complete > 1:
        cells = ["**total** (%d clouds)" % complete, str(total_points), ""]
        for s in sides:
            t = totals[s]
            pct = 100.0 * t["wrong"] / total_points if total_points else 0.0
            cells += ([fmt(t["seconds"]), fmt(t["peak_mb"], 1), "%d (%.3f%%)" % (t["wrong"], pct)]
                      if s in summed else ["-", "-", "-"])
        if python:
            cells.append("")
        total = lambda s, field: totals[s][field] if s in summed else None
        cells += [ratio(total("cgal", "seconds"), total("ours", "seconds")),
                  ratio(total("cgal", "peak_mb"), total("ours", "peak_mb"))]
        if python:
            cells += [ratio(total("open3d", "seconds"), total("ours", "seconds")),
                      ratio(total("open3d", "peak_mb"), total("ours", "peak_mb"))]
        print("| " + " | ".join(cells) + " |")

    # Failures in full, and the per-point check.
    failures = [(row, s) for row in rows for s in sides
                if row["sides"].get(s) and not row["sides"][s].get("ok") and not row["sides"][s].get("skipped")]
    if failures:
        print()
        for row, s in failures:
            side = row["sides"][s]
            tail = " / ".join(side.get("stderr_tail", []))
            print("- %s, noise %s, %s: %s%s" % (row["mesh"], row["noise"], SIDE_TITLES[s], side.get("reason"),
                                               (" (stderr: %s)" % tail) if tail else ""))
    checked = [row for row in rows if any("check" in side for side in row["sides"].values())]
    if checked:
        print()
        print("Per-point check against the input and the sampling truth (`.gt.xyz`, compare_cgal's measure): "
              "order kept, missing (zero or non-finite) normals, wrong normals.")
        print()
        print("| mesh | noise | " + " | ".join("%s order / missing / wrong vs truth" % SIDE_TITLES[s]
                                                for s in sides) + " |")
        print("|:---|---:|" + "---:|" * len(sides))
        for row in checked:
            cells = [row["mesh"], str(row["noise"])]
            for s in sides:
                check = row["sides"].get(s, {}).get("check")
                if check is None:
                    cells.append("-")
                elif "error" in check:
                    cells.append("unreadable")
                else:
                    cells.append("%s / %d / %s" % ("kept" if check["same_order"] else "CHANGED",
                                                   check["missing_normals"],
                                                   check.get("wrong_truth", "-")))
            print("| " + " | ".join(cells) + " |")
    if python:
        stages = [row["sides"]["open3d"]["stages"]["seconds"] for row in rows
                  if row["sides"].get("open3d", {}).get("stages")]
        if stages:
            print()
            print("Open3D inside its process, summed over %d clouds: import %.2f s, read %.2f s, orient %.2f s, "
                  "write %.2f s." % (len(stages), sum(x["import"] for x in stages), sum(x["read"] for x in stages),
                                    sum(x["orient"] for x in stages), sum(x["write"] for x in stages)))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
