"""Seconds per image through `jax3dc serve` against one `jax3dc predict` process per image, in one run.

Run from the repository root:  PYTHONPATH=. python3 bench/serve_load.py [--images 20] [--size 224]

N images of procedural objects are rendered as the demo's held-out records are (a data build's
plain look, one view of a factory object per category, ``data_pipeline.samples.object_records``).
Then, with the shipped models and default options:
  1. `jax3dc serve --port 0` starts; all N images are submitted at once (one POST each, without
     waiting for any prediction) and the bench polls until every job is done. Its seconds per
     image run from the server's start (process start, imports, the models' load) to the last
     job done, divided by N. The jobs must have run in the order they were submitted (each
     started after the one before it finished), and the server's memory peak (VmHWM) is read
     before it stops.
  2. N separate `jax3dc predict IMAGE --out DIR` processes, one after the other, one image each:
     each starts Python and loads the models again.
The ratio is the second's seconds per image over the first's. On a machine shared with other work
the load may differ between the two halves, so the CPU seconds per image (user + system, of the
server process and of the predict processes: contention changes them far less than wall time)
and their ratio are printed too. The bench also counts the images whose structure.json is the
same byte for byte both ways (greedy decoding: all of them).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
import uuid
from pathlib import Path

from data_pipeline.samples import factory_source, object_records
from jax3dc.factories import FACTORIES

ROOT = Path(__file__).resolve().parents[1]
POLL_S = 0.5


def render_images(folder: Path, count: int, size: int) -> list[Path]:
    """``count`` images, one per factory category (cycling, seed = its index), as a data build renders them."""
    folder.mkdir(parents=True, exist_ok=True)
    categories = sorted(FACTORIES)
    images = []
    for k in range(count):
        category = categories[k % len(categories)]
        record = object_records(factory_source(category, k), 1, k, size)[0]
        path = folder / f"{k:02d}_{category}.png"
        path.write_bytes(record.image_png)
        images.append(path)
    return images


def command(*args: str) -> list[str]:
    return [sys.executable, "-m", "jax3dc.cli", *args]


def child_env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def post_image(url: str, image: Path) -> dict:
    """POST /api/jobs with ``image`` as the form's file; the job's JSON."""
    boundary = uuid.uuid4().hex
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"image\"; filename=\"{image.name}\"\r\n"
            f"Content-Type: image/png\r\n\r\n").encode() + image.read_bytes() + f"\r\n--{boundary}--\r\n".encode()
    request = urllib.request.Request(f"{url}/api/jobs", data=body, method="POST",
                                     headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    with urllib.request.urlopen(request) as reply:
        return json.loads(reply.read())


def get_json(url: str) -> dict:
    with urllib.request.urlopen(url) as reply:
        return json.loads(reply.read())


def peak_memory_mb(pid: int) -> float:
    """The process's resident-memory peak (VmHWM), MB."""
    status = Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"VmHWM:\s+(\d+) kB", status).group(1)) / 1024


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of the process and its waited-for children so far (/proc/PID/stat)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return sum(int(v) for v in fields[11:15]) / os.sysconf("SC_CLK_TCK")


def children_cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def through_server(images: list[Path], out: Path) -> dict:
    """Seconds per image through `jax3dc serve`, the order the jobs ran in and the server's memory peak."""
    start = time.perf_counter()
    server = subprocess.Popen(command("serve", "--port", "0", "--no-open", "--out", str(out)), env=child_env(),
                              stdout=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        match = re.search(r"serving at (http://\S+?)/? ", line)
        if match is None:
            raise SystemExit(f"the server did not start: {line!r}")
        url = match.group(1)
        submitted = [post_image(url, image)["id"] for image in images]
        while True:
            jobs = {job["id"]: job for job in get_json(f"{url}/api/jobs")["jobs"]}
            if all(jobs[i]["state"] in ("done", "failed") for i in submitted):
                break
            time.sleep(POLL_S)
        seconds = time.perf_counter() - start
        memory = peak_memory_mb(server.pid)
        cpu = cpu_seconds(server.pid)
    finally:
        server.send_signal(signal.SIGINT)
        try:
            server.wait(timeout=60)
        except subprocess.TimeoutExpired:
            server.kill()
    numbers = [jobs[i]["number"] for i in submitted]
    return {"seconds": seconds, "cpu_seconds": cpu, "memory_mb": memory, "ids": submitted,
            "in_order": numbers == sorted(numbers) and len(set(numbers)) == len(numbers),
            "failed": [i for i in submitted if jobs[i]["state"] != "done"],
            "job_seconds": [jobs[i]["seconds"] for i in submitted]}


def one_process_each(images: list[Path], out: Path) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of N `jax3dc predict IMAGE --out DIR` processes, one after the other."""
    start, cpu = time.perf_counter(), children_cpu_seconds()
    for image in images:
        subprocess.run(command("predict", str(image), "--out", str(out / image.stem)), env=child_env(), check=False,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start, children_cpu_seconds() - cpu


def started_in_order(out: Path, ids: list[str]) -> bool:
    """Whether each job's done.json was written after the one submitted before it (it ran after it)."""
    times = [(out / i / "done.json").stat().st_mtime for i in ids if (out / i / "done.json").is_file()]
    return len(times) == len(ids) and times == sorted(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--images", type=int, default=20, help="how many images (default %(default)s)")
    parser.add_argument("--size", type=int, default=224, help="image side in pixels (default %(default)s)")
    parser.add_argument("--work", help="folder for the images and predictions (default: a temporary one)")
    args = parser.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="serve_load_"))
    images = render_images(work / "images", args.images, args.size)
    print(f"{len(images)} images of {args.size} px in {work / 'images'}; {os.cpu_count()} CPUs, "
          f"{platform.processor() or platform.machine()}", flush=True)

    served = through_server(images, work / "serve")
    per_served = served["seconds"] / len(images)
    in_order = served["in_order"] and started_in_order(work / "serve", served["ids"])
    cpu_served = served["cpu_seconds"] / len(images)
    job_seconds = sorted(s for s in served["job_seconds"] if s is not None)
    print(f"jax3dc serve: {served['seconds']:.1f} s for {len(images)} images from the server's start, "
          f"{per_served:.2f} s per image ({cpu_served:.2f} CPU s); a job's median {job_seconds[len(job_seconds) // 2]:.1f} s; "
          f"in submission order: {in_order}; failed: {len(served['failed'])}; "
          f"server memory peak {served['memory_mb']:.0f} MB", flush=True)

    separate, separate_cpu = one_process_each(images, work / "predict")
    per_process, cpu_process = separate / len(images), separate_cpu / len(images)
    print(f"jax3dc predict, one process per image: {separate:.1f} s, {per_process:.2f} s per image "
          f"({cpu_process:.2f} CPU s)", flush=True)
    same = sum((work / "serve" / i / "structure.json").is_file()
               and (work / "serve" / i / "structure.json").read_bytes()
               == (work / "predict" / image.stem / "structure.json").read_bytes()
               for i, image in zip(served["ids"], images) if (work / "predict" / image.stem / "structure.json").is_file())
    print(f"ratio: {per_process / per_served:.2f}x wall, {cpu_process / cpu_served:.2f}x CPU (one process per image / "
          f"the server); structure.json the same both ways: {same} of {len(images)}")
    print(json.dumps({"served_s_per_image": round(per_served, 2), "process_s_per_image": round(per_process, 2),
                      "ratio": round(per_process / per_served, 2), "served_cpu_s_per_image": round(cpu_served, 2),
                      "process_cpu_s_per_image": round(cpu_process, 2),
                      "cpu_ratio": round(cpu_process / cpu_served, 2), "in_order": in_order,
                      "server_peak_mb": round(served["memory_mb"]), "same_structures": same, "images": len(images)}))


if __name__ == "__main__":
    main()
