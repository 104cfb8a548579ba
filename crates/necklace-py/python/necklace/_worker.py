"""``python -m necklace._worker MESH --options JSON [--save-run DIR]``: one mesh of a
batch in this process (``necklace::batch::work``); its row on stdout as one JSON line.
:func:`necklace.batch` starts it, one process per mesh, and watches it."""

from __future__ import annotations

import argparse
import sys

from ._necklace import batch_work


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m necklace._worker")
    parser.add_argument("mesh")
    parser.add_argument("--options", required=True)
    parser.add_argument("--save-run", default=None)
    args = parser.parse_args(argv)
    sys.stdout.write(batch_work(args.mesh, args.options, args.save_run))
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
