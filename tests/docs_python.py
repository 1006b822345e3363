#!/usr/bin/env python3
"""Runs the Python examples of README.md and docs/guide/*.md and compares what they print with
what the pages show, as tests/cli/docs.rs does for the command line.

The convention: a fenced block whose info string is `pycon` is a doctest (`>>> ` statements,
`... ` continuations, the expected output below each). The blocks of one page run in order in
one namespace, in a temporary directory holding a link to the repository's `fixtures/` (the
examples write files there). Compared as doctest compares, with NORMALIZE_WHITESPACE (a long
output may be wrapped on the page) and nothing else loosened. A block that calls
`to_roboticstoolbox` is skipped, saying so, where `roboticstoolbox` does not import.

Needs the `urdf_dh` wheel, numpy and pandas installed (.ci/run's Python step):
    python tests/docs_python.py          # exit 0 when every example prints what its page shows
"""

import doctest
import os
import re
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLOCK = re.compile(r"^```pycon[^\n]*\n(.*?)^```$", re.M | re.S)


def pages():
    return [ROOT / "README.md"] + sorted((ROOT / "docs" / "guide").glob("*.md"))


def has_rtb():
    try:
        import roboticstoolbox  # noqa: F401
    except Exception:  # an import error of any kind: the tests say so and skip
        return False
    return True


def main():
    rtb = has_rtb()
    flags = doctest.NORMALIZE_WHITESPACE
    parser = doctest.DocTestParser()
    failed = attempted = skipped = 0
    for page in pages():
        text = page.read_text(encoding="utf-8")
        blocks = list(BLOCK.finditer(text))
        if not blocks:
            continue
        name = str(page.relative_to(ROOT))
        globs = {"__name__": "__docs__"}
        with tempfile.TemporaryDirectory() as tmp:
            os.symlink(ROOT / "fixtures", Path(tmp) / "fixtures")
            cwd = os.getcwd()
            os.chdir(tmp)
            try:
                for m in blocks:
                    line = text.count("\n", 0, m.start()) + 1
                    if "to_roboticstoolbox" in m.group(1) and not rtb:
                        print(f"{name}:{line}: skipped: roboticstoolbox-python does not import")
                        skipped += 1
                        continue
                    test = parser.get_doctest(m.group(1), globs, f"{name}:{line}", name, line)
                    runner = doctest.DocTestRunner(optionflags=flags)
                    result = runner.run(test, out=sys.stdout.write, clear_globs=False)
                    globs.update(test.globs)  # DocTest works on a copy: the next block sees these
                    failed += result.failed
                    attempted += result.attempted
            finally:
                os.chdir(cwd)
    print(f"docs_python: {attempted} examples, {failed} failed, {skipped} block(s) skipped")
    return 1 if failed or attempted == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
