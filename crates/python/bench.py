"""Time of urdf_dh.extract on the Franka Panda fixture (1000-sample verification, YAML written
and proved), to compare with the Rust call of `cargo bench --bench cli -- "in process"`
("extract panda --format yaml (in process)").

    python crates/python/bench.py            # after maturin develop --release / pip install

Goal: within 10 % of the Rust call plus 20 us (the Python layer: argument conversion, numpy
arrays of base and tool, the rows as objects).

Measured 2026-11-23 on the shared 2-core machine (load ~3): Python 953-959 us median per call;
criterion "extract panda --format yaml (in process)" 1.10 ms [1.03, 1.19] (text format 832 us).
The Python call skips clap and the writer to a buffer, so it is within the goal.
"""

import statistics
import sys
import time
from pathlib import Path

import urdf_dh

PANDA = Path(__file__).resolve().parents[2] / "fixtures" / "robots" / "franka_panda" / "robot.urdf"


def main() -> int:
    path = str(PANDA)
    table = urdf_dh.extract(path)
    assert table.verification["passed"]
    for _ in range(20):  # warm-up
        urdf_dh.extract(path)
    runs = []
    for _ in range(15):
        n = 50
        t0 = time.perf_counter()
        for _ in range(n):
            urdf_dh.extract(path)
        runs.append((time.perf_counter() - t0) / n)
    print(
        f"urdf_dh.extract(panda, samples=1000): median {statistics.median(runs) * 1e6:.1f} us, "
        f"min {min(runs) * 1e6:.1f} us over {len(runs)} batches of 50"
    )
    idyntree_side_by_side(path)
    q = [0.1] * len(table.rows)
    n = 20000
    t0 = time.perf_counter()
    for _ in range(n):
        table.fk(q)
    print(f"Table.fk (7 joints): {(time.perf_counter() - t0) / n * 1e6:.2f} us")
    return 0


def median_us(call, batches: int = 15, n: int = 50) -> "tuple[float, float]":
    """Median and minimum time per call of ``call`` (microseconds), after a warm-up."""
    for _ in range(20):
        call()
    runs = []
    for _ in range(batches):
        t0 = time.perf_counter()
        for _ in range(n):
            call()
        runs.append((time.perf_counter() - t0) / n)
    return statistics.median(runs) * 1e6, min(runs) * 1e6


def idyntree_side_by_side(path: str) -> None:
    """iDynTree's URDF load + DH extraction (no verification) against urdf_dh.extract without
    and with its verification, in the same process (``pip install idyntree``; skipped without).
    iDynTree prints a line per non-unique DH choice on standard error: redirect it."""
    try:
        import idyntree.bindings as idt
    except ImportError:
        print("iDynTree side by side: skipped (pip install idyntree to compare)")
        return

    def idyntree_extract() -> None:
        loader = idt.ModelLoader()
        if not loader.loadModelFromFile(path):
            raise RuntimeError("iDynTree could not load the Panda")
        chain = idt.DHChain()
        if not idt.ExtractDHChainFromModel(loader.model(), "panda_link0", "panda_link8", chain):
            raise RuntimeError("iDynTree could not extract the Panda's DH chain")

    for label, call in [
        ("iDynTree load + ExtractDHChainFromModel", idyntree_extract),
        ("urdf_dh.extract(samples=0), no verification", lambda: urdf_dh.extract(path, samples=0)),
        ("urdf_dh.extract(samples=1000), verified", lambda: urdf_dh.extract(path)),
    ]:
        med, low = median_us(call)
        print(f"{label}: median {med:.1f} us, min {low:.1f} us")


if __name__ == "__main__":
    sys.exit(main())
