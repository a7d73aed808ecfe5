"""Trajectory text files: one "stamp x y theta" line per pose (the offline
runner's trajectory_*.txt, the monitor's outputs); # comments and blank
lines skipped."""


def read_rows(path, columns=None):
    """Every content line as a list of floats; with `columns`, a line with
    another number of values is an error naming the file."""
    rows = []
    with open(path) as f:
        for line in f:
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            values = [float(v) for v in line.split()]
            if columns is not None and len(values) != columns:
                raise RuntimeError("%s: expected %d columns, got %d" % (path, columns, len(values)))
            rows.append(values)
    return rows


def rows_by_stamp(path, columns=None):
    """The same keyed by the stamp (first value) rounded to the microsecond."""
    return {round(values[0], 6): values for values in read_rows(path, columns)}
