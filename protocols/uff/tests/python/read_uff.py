"""Reads a universal file metaplate-uff wrote with pyuff and checks it against the values written.

    read_uff.py FILE EXPECTED.json

EXPECTED lists the units, the nodes and, for each function in file order, its format, precision, type, nodes
and values (complex as [re, im] pairs), as written before encoding. Exits non-zero with a message on the first
difference beyond the format's precision (the bounds of the crate documentation).
"""

import json
import sys

import numpy as np
import pyuff

path, expected_path = sys.argv[1], sys.argv[2]
with open(expected_path) as f:
    expected = json.load(f)
sets = pyuff.UFF(path).read_sets()
assert len(sets) == 2 + len(expected["functions"]), f"{len(sets)} datasets"

units = sets[0]
assert units["type"] == 164 and units["units_code"] == 1, units
assert (units["length"], units["force"], units["temp"], units["temp_offset"]) == (1.0, 1.0, 1.0, 273.15), units

nodes = sets[1]
assert nodes["type"] == 2411
assert list(nodes["node_nums"]) == expected["node_labels"], nodes["node_nums"]
for axis, name in enumerate("xyz"):
    assert list(nodes[name]) == [p[axis] for p in expected["node_positions_m"]], (name, nodes[name])

BOUND = {("ascii", "single"): 5e-6, ("ascii", "double"): 5e-12, ("binary", "single"): 2.0**-24, ("binary", "double"): 0.0}
for i, (function, read) in enumerate(zip(expected["functions"], sets[2:])):
    what = f"function {i} ({function['format']}, {function['precision']}, type {function['function_type']})"
    assert read["type"] == 58, what
    assert read["binary"] == (function["format"] == "binary"), what
    assert read["func_type"] == function["function_type"], what
    assert (read["rsp_node"], read["rsp_dir"], read["ref_node"], read["ref_dir"]) == (
        function["response_node"], 3, function["reference_node"], 3), what
    written = np.array(function["values"])
    if written.ndim == 2:
        written = written[:, 0] + 1j * written[:, 1]
    data = np.asarray(read["data"])
    assert data.shape == written.shape, (what, data.shape, written.shape)
    assert np.iscomplexobj(data) == np.iscomplexobj(written), what
    bound = BOUND[(function["format"], function["precision"])]
    for part in (np.real, np.imag):
        error = np.abs(part(data) - part(written))
        allowed = bound * np.abs(part(written)) * (1 + 1e-9) + np.finfo(float).eps * np.abs(part(written))
        assert np.all(error <= allowed), (what, part(data), part(written))
    step = read["x"][1] - read["x"][0]
    assert abs(step - function["abscissa_step"]) <= 5e-6 * function["abscissa_step"] * 1.001, (what, step)

print(f"pyuff read {len(sets)} datasets: units, {len(nodes['node_nums'])} nodes, {len(sets) - 2} functions")
