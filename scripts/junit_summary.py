"""Print one closing line 'N passed, N failed, N skipped' summed over pytest JUnit XML reports.

scripts/test.sh runs the suite in two pytest processes (see there); this gives the single closing
line a reader (and CI) expects. Exit status 1 when any report is missing or counts a failure/error.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET  # our own pytest output, not untrusted input
from pathlib import Path


def main(paths: list[str]) -> int:
    passed = failed = skipped = 0
    ok = True
    for name in paths:
        path = Path(name)
        if not path.is_file():
            print(f"missing test report: {path}", file=sys.stderr)
            ok = False
            continue
        root = ET.parse(path).getroot()
        for suite in root.iter("testsuite"):
            tests = int(suite.get("tests", 0))
            f = int(suite.get("failures", 0)) + int(suite.get("errors", 0))
            s = int(suite.get("skipped", 0))
            passed += tests - f - s
            failed += f
            skipped += s
    print(f"{passed} passed, {failed} failed, {skipped} skipped")
    return 0 if ok and failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
