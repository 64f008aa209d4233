#!/usr/bin/env python3
"""Runs the README's shell blocks that use only examples/ (not the set-up and test commands, which
need a fresh machine and apt), with the build's ffcube, in a scratch directory: so that the front
door's commands cannot go stale. Each block must exit 0, and each output file it names with -o,
--groups, --sky, --view3d, --report or --objects must exist and be non-empty afterwards.

    python3 tests/docs/run_readme_blocks.py SOURCE_DIR BUILD_DIR
"""
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

OUTPUT_FLAGS = {"-o", "--output", "--groups", "--sky", "--view3d", "--report", "--objects", "--render", "--radiosity"}


def blocks(readme: str):
    for m in re.finditer(r"```sh\n(.*?)```", readme, re.S):
        yield m.group(1)


def main() -> int:
    source, build = pathlib.Path(sys.argv[1]).resolve(), pathlib.Path(sys.argv[2]).resolve()
    readme = (source / "README.md").read_text()
    ran = 0
    for block in blocks(readme):
        if "tools/setup.sh" in block or "tools/test.sh" in block:
            continue  # the fresh-machine commands: CI runs the test one
        for line in block.strip().splitlines():
            words = shlex.split(line)
            if not words or words[0] != "./build/ffcube":
                print(f"README block line not of the runnable kind: {line!r}", file=sys.stderr)
                return 1
            with tempfile.TemporaryDirectory() as tmp:
                tmpdir = pathlib.Path(tmp)
                (tmpdir / "examples").symlink_to(source / "examples")
                (tmpdir / "build").symlink_to(build)
                r = subprocess.run(words, cwd=tmpdir, capture_output=True, text=True, timeout=900)
                if r.returncode != 0:
                    print(f"FAILED ({r.returncode}): {line}\n{r.stdout}{r.stderr}", file=sys.stderr)
                    return 1
                for flag, value in zip(words, words[1:]):
                    if flag in OUTPUT_FLAGS and not value.startswith("/dev/"):
                        out = tmpdir / value
                        if not out.is_file() or out.stat().st_size == 0:
                            print(f"FAILED: {line}: {value} missing or empty", file=sys.stderr)
                            return 1
                ran += 1
                print(f"ok: {line}")
    if ran < 4:
        print(f"only {ran} runnable README lines found: the test looks at the wrong file", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
