"""Pick N HouseExpo floor plans from a local copy of the dataset into a folder a campaign can glob.

HouseExpo (https://github.com/TeaganLi/HouseExpo) ships its 35,126 plans as ``HouseExpo/json.tar.gz`` in a
repository under the MIT licence, but the plans are derived from SUNCG (HouseExpo's README: "built on SUNCG
dataset"), which came with its own terms of use and was withdrawn in 2019; whether the MIT licence can cover
the derived plans is not clear, so swarm ships no HouseExpo plan (its tests use the hand-made plans in
``examples/plans/``, written in the same format). Get the dataset yourself::

    git clone https://github.com/TeaganLi/HouseExpo && tar -xzf HouseExpo/HouseExpo/json.tar.gz -C /data

then::

    python benchmarks/experiments/fetch_houseexpo.py /data/json -n 20 -o plans/            # a seeded sample
    python benchmarks/experiments/fetch_houseexpo.py HouseExpo/HouseExpo/json.tar.gz \\
        --ids HouseExpo/experiments/map_id_test.txt -o plans/                              # the paper's test set
    python benchmarks/experiments/fetch_houseexpo.py /data/json -n 20 -o plans/ --npz --scale 2.5

SOURCE is the extracted ``json`` folder or the ``json.tar.gz`` itself (read without extracting). The sample is
``random.Random(seed).sample`` of the sorted plan ids, so the same seed picks the same plans; plans that do not
import (a degenerate polygon) are skipped and replaced by the next in the sample. ``--npz`` also imports each
plan (``maps.io.import_houseexpo``, at ``--scale``) next to its JSON. A campaign then reads the folder::

    map = [{files = "plans/*.json", label = "houseexpo", params = {scale = 2.5}}]
"""

from __future__ import annotations

import argparse
import random
import sys
import tarfile
from collections.abc import Iterator
from pathlib import Path


def plan_sources(source: Path) -> dict[str, object]:
    """Plan id -> a zero-argument reader of its JSON bytes, from a folder or a .tar.gz."""
    if source.is_dir():
        return {p.stem: p.read_bytes for p in sorted(source.glob("*.json"))}
    archive = tarfile.open(source, "r:gz")
    members = {Path(m.name).stem: m for m in archive.getmembers() if m.isfile() and m.name.endswith(".json")}
    return {pid: (lambda m=m: archive.extractfile(m).read()) for pid, m in sorted(members.items())}


def choose(ids: list[str], n: int | None, seed: int, wanted: Path | None) -> Iterator[str]:
    if wanted is not None:
        yield from (line.strip() for line in wanted.read_text().splitlines() if line.strip())
        return
    order = random.Random(seed).sample(sorted(ids), len(ids))
    yield from order


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", type=Path, help="HouseExpo's json folder or json.tar.gz")
    ap.add_argument("-o", "--output", type=Path, required=True)
    ap.add_argument("-n", type=int, default=10, help="how many plans (ignored with --ids)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--ids", type=Path, default=None, help="a file of plan ids, one a line (HouseExpo's map_id_*.txt)")
    ap.add_argument("--npz", action="store_true", help="also write each plan imported as a swarm .npz")
    ap.add_argument("--scale", type=float, default=1.0, help="with --npz: the import scale")
    args = ap.parse_args(argv)

    from maps.io import import_houseexpo
    from swarm.base.errors import InvalidInput

    sources = plan_sources(args.source)
    if not sources:
        print(f"no *.json plans in {args.source}", file=sys.stderr)
        return 2
    args.output.mkdir(parents=True, exist_ok=True)
    kept = 0
    limit = None if args.ids is not None else args.n
    for pid in choose(list(sources), limit, args.seed, args.ids):
        if limit is not None and kept >= limit:
            break
        if pid not in sources:
            print(f"skip {pid}: not in {args.source}", file=sys.stderr)
            continue
        path = args.output / f"{pid}.json"
        path.write_bytes(sources[pid]())
        try:
            m = import_houseexpo(path, scale=args.scale)
        except InvalidInput as exc:
            print(f"skip {pid}: {exc}", file=sys.stderr)
            path.unlink()
            continue
        if args.npz:
            from maps.io import save_npz

            save_npz(m, path.with_suffix(".npz"))
        kept += 1
        print(f"{path}  {m.summary()}")
    print(f"{kept} plans in {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
