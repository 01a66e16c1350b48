#!/usr/bin/env python3
"""Encodes a scan with its jobs run on a Dask distributed cluster.

    dask_encode.py SCAN -o MODEL.spg --scheduler tcp://HOST:8786 [options] [-- ENCODE OPTIONS]

The same plan as `stipple encode`, in three steps (docs/encoder.md "On a
cluster"):
  1. here: `stipple encode SCAN --plan-only WORK` writes the partitions and
     WORK/jobs.txt;
  2. on the cluster's workers: `stipple encode-part WORK ID` for every job,
     each submitted as a Dask task, retried when it fails (--retries);
  3. here: every part's CRC-32 checked against the one its job reported
     (a part that fails the check is run again once), then
     `stipple encode --merge WORK -o MODEL.spg`.
The .spg is byte-identical to `stipple encode SCAN -o MODEL.spg` with the
same options. WORK must be a folder every worker sees at the same path (a
shared file system); it is removed at the end unless --keep.

Exits 0 on success; 1 with a message naming the job, the part or the step
that failed.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zlib


def run_part(stipple, work, job, threads):
    """One job, on a worker: returns (job, the part's CRC-32 as printed)."""
    command = [stipple, "encode-part", work, str(job)]
    if threads:
        command += ["--threads", str(threads)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"job {job}: {' '.join(command)} exited {done.returncode}: {done.stderr.strip()}")
    # "WORK/part-00012.nodes: 1,234 points, crc32 89abcdef, 0.12 s"
    words = done.stdout.split()
    crc = words[words.index("crc32") + 1].rstrip(",")
    return job, int(crc, 16)


def part_crc(work, job):
    """The CRC-32 a part file carries at its end, checked against its bytes; None when they disagree."""
    path = os.path.join(work, f"part-{job:05d}.nodes")
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    if len(data) < 4:
        return None
    stored = int.from_bytes(data[-4:], "little")
    return stored if zlib.crc32(data[:-4]) == stored else None


def read_jobs(work):
    jobs = []
    with open(os.path.join(work, "jobs.txt")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                jobs.append(int(line.split()[0]))
    return jobs


def main():
    parser = argparse.ArgumentParser(
        description="Encode a scan with stipple, its partition jobs run on a Dask distributed cluster.",
        epilog="Options after -- go to stipple encode (--memory, --partition-points, --leaf-size, ...).")
    parser.add_argument("scan")
    parser.add_argument("-o", "--output", required=True, help="the .spg to write")
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--scheduler", help="the Dask scheduler's address, tcp://HOST:PORT")
    where.add_argument("--scheduler-file", help="the file dask-scheduler --scheduler-file wrote")
    parser.add_argument("--stipple", default=shutil.which("stipple") or "stipple",
                        help="the stipple program, at the same path on every worker (default: on PATH)")
    parser.add_argument("--work", help="the plan's folder, shared with the workers (default: a new one beside the output)")
    parser.add_argument("--retries", type=int, default=2, help="times a failed job is run again (default 2)")
    parser.add_argument("--threads", type=int, default=0, help="threads a job uses (default: the worker's cores)")
    parser.add_argument("--keep", action="store_true", help="keep the plan's folder")
    parser.add_argument("--wait-workers", type=int, default=1, metavar="N",
                        help="wait (up to 60 s) until N workers have joined before submitting (default 1)")
    argv = sys.argv[1:]
    encode_options = argv[argv.index("--") + 1:] if "--" in argv else []
    args = parser.parse_args(argv[:argv.index("--")] if "--" in argv else argv)

    try:
        from distributed import Client, as_completed
    except ImportError:
        sys.exit("dask_encode.py: Dask distributed is not installed (Debian: apt install python3-distributed)")

    out_dir = os.path.dirname(os.path.abspath(args.output))
    work = os.path.abspath(args.work) if args.work else tempfile.mkdtemp(prefix="stipple-plan.", dir=out_dir)
    start = time.monotonic()
    try:
        plan = subprocess.run([args.stipple, "encode", args.scan, "--plan-only", work, "--quiet", *encode_options])
        if plan.returncode != 0:
            sys.exit(f"dask_encode.py: planning {args.scan} failed (stipple encode --plan-only exited {plan.returncode})")
        jobs = read_jobs(work)
        client = Client(args.scheduler) if args.scheduler else Client(scheduler_file=args.scheduler_file)
        try:
            client.wait_for_workers(n_workers=args.wait_workers, timeout=60)
        except Exception:
            sys.exit(f"dask_encode.py: fewer than {args.wait_workers} workers joined {client.scheduler.address} in 60 s")
        workers = len(client.scheduler_info()["workers"])
        print(f"dask_encode.py: {len(jobs)} jobs on {workers} workers ({client.scheduler.address})", flush=True)
        futures = client.map(run_part, [args.stipple] * len(jobs), [work] * len(jobs), jobs,
                             [args.threads] * len(jobs), retries=args.retries, pure=False)
        reported = {}
        for future in as_completed(futures):
            try:
                job, crc = future.result()
            except Exception as e:  # the job failed more than --retries times
                sys.exit(f"dask_encode.py: {e}")
            reported[job] = crc
        # Each part as its job reported it, or run once more.
        for job in jobs:
            if part_crc(work, job) != reported[job]:
                print(f"dask_encode.py: part {job} does not match the CRC-32 its job reported: running it again", flush=True)
                _, crc = client.submit(run_part, args.stipple, work, job, args.threads, pure=False).result()
                if part_crc(work, job) != crc:
                    sys.exit(f"dask_encode.py: part {job} ({work}/part-{job:05d}.nodes) fails its CRC-32 check twice")
        client.close()
        merge = subprocess.run([args.stipple, "encode", "--merge", work, "-o", args.output, "--quiet"])
        if merge.returncode != 0:
            sys.exit(f"dask_encode.py: merging {work} failed (stipple encode --merge exited {merge.returncode})")
        print(f"dask_encode.py: {args.output} from {len(jobs)} jobs in {time.monotonic() - start:.2f} s", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
