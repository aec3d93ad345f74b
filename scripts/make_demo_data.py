#!/usr/bin/env python3
"""Regenerate the bundled demo data byte-identically: ``demo_data/*.h5`` and ``maps/<scene>_{cloud.ply,edges.npz}``.

Each recording is one ``evpose simulate`` run (the equivalent command is
recorded below and printed); the raw clouds and true edges depend only on the
scene and the seed, so the landing variants share ``maps/landing_*``.

    python scripts/make_demo_data.py                 # write into the repository
    python scripts/make_demo_data.py --out /tmp/d    # write elsewhere
    python scripts/make_demo_data.py --check         # regenerate into a temp folder and compare SHA-256 with the repo's files

Budget: all demo data + maps <= 40 MB (checked at the end).
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BUDGET_MB = 40.0

# name, scenario, seconds, resolution, seed. Equivalent CLI:
#   evpose simulate --scenario SCENARIO --out demo_data/NAME.h5 --seconds S --resolution WxH --seed N
DEMOS = [
    ("landing", "landing", 4.0, (346, 260), 0),
    ("landing_fast", "landing_fast", 2.5, (346, 260), 0),
    ("landing_dynamic", "landing_dynamic", 3.0, (346, 260), 0),
    ("indoor", "indoor", 5.0, (346, 260), 0),
]
# scene -> the demo whose (seed-determined) cloud and edges go to maps/<scene>_*
MAP_SOURCES = {"landing": "landing", "indoor": "indoor"}


def command(name, scenario, seconds, res, seed) -> str:
    return f"evpose simulate --scenario {scenario} --out demo_data/{name}.h5 --seconds {seconds:g} --resolution {res[0]}x{res[1]} --seed {seed} --no-cloud"


def generate(root: Path, only: list[str] | None = None) -> list[Path]:
    from evpose.sim import SimulationConfig, simulate
    from evpose.sim.lidar import write_cloud_ply, write_edges_npz
    from evpose.sim.outputs import write_simulation

    written = []
    for name, scenario, seconds, res, seed in DEMOS:
        if only and name not in only:
            continue
        print(f"$ {command(name, scenario, seconds, res, seed)}", flush=True)
        t0 = time.perf_counter()
        result = simulate(SimulationConfig(scenario=scenario, seconds=seconds, resolution=res, seed=seed))
        written += write_simulation(result, root / "demo_data" / f"{name}.h5", cloud=False).values()
        for scene, source in MAP_SOURCES.items():
            if source == name:
                write_cloud_ply(root / "maps" / f"{scene}_cloud.ply", result.cloud_points, result.cloud_intensity)
                write_edges_npz(root / "maps" / f"{scene}_edges.npz", result.edges, result.albedo_edges)
                written += [root / "maps" / f"{scene}_cloud.ply", root / "maps" / f"{scene}_edges.npz"]
        n = len(result.recording.events)
        print(f"  {n} events ({n / seconds / 1e6:.3f} Mev/s), {result.stats['renders']} renders, {time.perf_counter() - t0:.0f} s", flush=True)
    return written


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=REPO, help="root folder receiving demo_data/ and maps/")
    ap.add_argument("--check", action="store_true", help="regenerate into a temp folder and compare with --out")
    ap.add_argument("--only", nargs="*", help="demo names to (re)generate")
    args = ap.parse_args(argv)
    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            fresh = generate(Path(tmp), args.only)
            bad = 0
            for p in fresh:
                ref = args.out / p.relative_to(tmp)
                same = ref.exists() and digest(ref) == digest(p)
                bad += not same
                print(f"{'same' if same else 'DIFFERENT'}  {ref.relative_to(args.out)}")
            return 1 if bad else 0
    files = generate(args.out, args.only)
    for p in files:
        p.chmod(0o644)  # atomic writes create private (0600) temporaries; demo data is for everyone
    total = 0
    for p in sorted(set(files)):
        size = p.stat().st_size
        total += size
        print(f"{digest(p)[:16]}  {size / 1e6:7.2f} MB  {p.relative_to(args.out)}")
    all_files = list((args.out / "demo_data").glob("*")) + list((args.out / "maps").glob("*_cloud.ply")) + list((args.out / "maps").glob("*_edges.npz"))
    total_all = sum(p.stat().st_size for p in all_files if p.is_file())
    print(f"demo data + maps: {total_all / 1e6:.1f} MB (budget {BUDGET_MB:g} MB)")
    return 0 if total_all <= BUDGET_MB * 1e6 else 1


if __name__ == "__main__":
    sys.exit(main())
