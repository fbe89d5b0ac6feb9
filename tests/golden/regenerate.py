"""Record the golden ``--json`` outputs (tests/golden/*.json) after an intended change."""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from golden_cases import CASES, HERE, run_case  # noqa: E402


def main() -> None:
    names = sys.argv[1:] or list(CASES)
    for name in names:
        with tempfile.TemporaryDirectory() as tmp:
            data = run_case(name, Path(tmp))
        (HERE / f"{name}.json").write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
        print(f"wrote {name}.json")


if __name__ == "__main__":
    main()
