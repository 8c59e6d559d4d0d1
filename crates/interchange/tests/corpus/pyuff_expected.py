"""Writes pyuff_expected.json: what pyuff 2.5.8 reads from each universal file of this corpus, for the import tests
to compare with (run with the project's .venv: `.venv/bin/python crates/interchange/tests/corpus/pyuff_expected.py`).

Per file: each dataset's type as pyuff lists it; per dataset 58 its function type, reference and response node and
direction, data types, units labels, abscissa step, the number of values, and the values themselves (all of them up to
64, else the first 32, the last 32 and the sum of the absolute values). A file pyuff cannot read is noted with its
error."""

import json
import pathlib

import numpy as np
import pyuff

HERE = pathlib.Path(__file__).parent
KEEP = 64


def values(data):
    data = np.asarray(data)
    as_pairs = lambda a: [[float(v.real), float(v.imag)] for v in a] if np.iscomplexobj(a) else [float(v) for v in a]
    if len(data) <= KEEP:
        return {"all": as_pairs(data)}
    return {"first": as_pairs(data[:32]), "last": as_pairs(data[-32:]), "abs_sum": float(np.abs(data).sum())}


out = {}
for path in sorted(HERE.glob("*.uff")):
    entry = {}
    try:
        uff = pyuff.UFF(str(path))
        entry["set_types"] = [int(t) for t in uff.get_set_types()]
        functions = []
        for i, t in enumerate(entry["set_types"]):
            if t != 58:
                continue
            d = uff.read_sets(i)
            functions.append({
                "index": i,
                "func_type": int(d["func_type"]),
                "rsp_node": int(d["rsp_node"]), "rsp_dir": int(d["rsp_dir"]),
                "ref_node": int(d["ref_node"]), "ref_dir": int(d["ref_dir"]),
                "ord_data_type": int(d["ord_data_type"]),
                "ordinate_spec_data_type": int(d["ordinate_spec_data_type"]),
                "ordinate_axis_units_lab": d["ordinate_axis_units_lab"],
                "abscissa_inc": float(d.get("abscissa_inc", 0.0)),
                "num_pts": int(d["num_pts"]),
                "values": values(d["data"]),
            })
        entry["functions"] = functions
    except Exception as e:  # noqa: BLE001 - recorded, not hidden: the test checks what metaplate says of it.
        entry["pyuff_error"] = f"{type(e).__name__}: {e}"
    out[path.name] = entry

(HERE / "pyuff_expected.json").write_text(json.dumps(out, indent=1, ensure_ascii=False) + "\n")
