#!/usr/bin/env python3
# Copies the tables `make benchmark` writes into the documentation, so that the
# published figures are the measured ones and never retyped by hand.
#
#   OUTPUT_DIR/summary.md  -> docs/results.md and README.md, between
#                             <!-- benchmark:summary:begin --> and
#                             <!-- benchmark:summary:end -->
#   OUTPUT_DIR/details.md  -> docs/results.md, between
#                             <!-- benchmark:details:begin --> and
#                             <!-- benchmark:details:end -->
#
# usage: tools/ci/update_results_doc.py [OUTPUT_DIR]   (default: output/benchmark)
#
# Only the table lines (those starting with "|") of each file are copied; the
# marker lines stay, everything outside them is left as it is. A missing
# summary.md, a file without a table, or a document without its markers is an
# error (exit 1) and no document is changed. A missing details.md leaves the
# details table as it was (a warning says so). Each document is written to a
# temporary file beside it and renamed over it. Python 3 standard library only.
import os
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def read_table(path):
    """The table lines of a Markdown file, or an error text."""
    with open(path, encoding="utf-8") as f:
        lines = [line.rstrip("\n") for line in f]
    table = [line for line in lines if line.lstrip().startswith("|")]
    if len(table) < 2:
        return None, "%s holds no table" % path
    return table, None


def replace_between(text, name, table, path):
    """text with the lines between the markers of `name` replaced by table."""
    begin = "<!-- benchmark:%s:begin -->" % name
    end = "<!-- benchmark:%s:end -->" % name
    lines = text.split("\n")
    starts = [i for i, line in enumerate(lines) if line.strip() == begin]
    ends = [i for i, line in enumerate(lines) if line.strip() == end]
    if len(starts) != 1 or len(ends) != 1 or ends[0] < starts[0]:
        return None, "%s: expected one %s followed by one %s" % (path, begin, end)
    # Blank lines around the table: Markdown then reads it as a block of its own.
    new = lines[: starts[0] + 1] + [""] + table + [""] + lines[ends[0]:]
    return "\n".join(new), None


def write_atomically(path, text):
    folder = os.path.dirname(path)
    fd, tmp = tempfile.mkstemp(prefix=".update_results_", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.chmod(tmp, os.stat(path).st_mode & 0o777)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def main(argv):
    if len(argv) > 2 or (len(argv) == 2 and argv[1] in ("-h", "--help")):
        print("usage: tools/ci/update_results_doc.py [OUTPUT_DIR]   (default: output/benchmark)")
        return 0 if len(argv) == 2 else 2
    out_dir = argv[1] if len(argv) == 2 else os.path.join(ROOT, "output", "benchmark")
    summary_path = os.path.join(out_dir, "summary.md")
    details_path = os.path.join(out_dir, "details.md")
    if not os.path.isfile(summary_path):
        print("update_results_doc: %s not found (run make benchmark first)" % summary_path,
              file=sys.stderr)
        return 1
    summary, error = read_table(summary_path)
    details = None
    if error is None and os.path.isfile(details_path):
        details, error = read_table(details_path)
    elif error is None:
        print("update_results_doc: %s not found; the details table is left as it was"
              % details_path, file=sys.stderr)
    if error:
        print("update_results_doc: " + error, file=sys.stderr)
        return 1

    targets = [(os.path.join(ROOT, "docs", "results.md"), ["summary", "details"]),
               (os.path.join(ROOT, "README.md"), ["summary"])]
    tables = {"summary": summary, "details": details}
    updated = []
    for path, names in targets:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        for name in names:
            if tables[name] is None:
                continue
            text, error = replace_between(text, name, tables[name], path)
            if error:
                print("update_results_doc: " + error, file=sys.stderr)
                return 1
        updated.append((path, text))
    # Every document was checked before any is written.
    for path, text in updated:
        write_atomically(path, text)
        print("update_results_doc: %s" % os.path.relpath(path, ROOT))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
