#!/usr/bin/env python3
"""Summarises the JUnit XML files that gtest and rostest wrote.

Prints each failed test case with its message, then one closing line
`Summary: N passed, N failed, N skipped`, and exits non-zero when anything
failed or nothing ran at all.
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def main(results_dir):
    files = sorted(glob.glob(os.path.join(results_dir, "**", "*.xml"), recursive=True))
    passed, failed, skipped = 0, 0, 0
    failures = []
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as err:
            failed += 1
            failures.append((os.path.basename(path), f"unreadable result file: {err}"))
            continue
        for case in root.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            problems = case.findall("failure") + case.findall("error")
            if problems:
                failed += 1
                text = (problems[0].get("message") or problems[0].text or "").strip()
                failures.append((name, text.splitlines()[0] if text else "failed"))
            elif (case.find("skipped") is not None or case.get("status") == "notrun"
                  or case.get("result") == "skipped"):
                skipped += 1
            else:
                passed += 1
    for name, text in failures:
        print(f"FAILED {name}: {text}")
    print(f"Summary: {passed} passed, {failed} failed, {skipped} skipped")
    if not files or passed == 0:
        print(f"test_summary: no test results found under {results_dir}", file=sys.stderr)
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
