"""Run the JAX and PyTorch checks and ``symkin bench diff`` on the GPU, when there is one
(:mod:`symkin.bench.gpu`); without a GPU print so and exit 0.

    python scripts/gpu_check.py [--robot panda] [--batches 1,1024,100000] [--no-bench]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this checkout's symkin

from symkin.bench.gpu import run_gpu_check  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot", default="panda", help="the robot of the benchmark (default panda)")
    p.add_argument("--batches", default="1,1024,100000", help="benchmark batch sizes, comma separated")
    p.add_argument("--no-bench", action="store_true", help="the checks only")
    args = p.parse_args(argv)
    batches = tuple(int(b) for b in args.batches.split(","))
    return run_gpu_check(bench_robot=args.robot, batches=batches, bench=not args.no_bench)


if __name__ == "__main__":
    raise SystemExit(main())
