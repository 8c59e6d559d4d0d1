"""Prints, as JSON on stdout, what pyuff reads from a universal file: per dataset 58 its response and reference
node and direction, ordinate data type, abscissa step and values (complex as [re, im] pairs); per dataset 2411 its nodes;
dataset 151's model name, description and programs.

    read_uff_values.py FILE
"""

import json
import sys

import numpy as np
import pyuff

out = {"functions": [], "nodes": {}, "headers": []}
for s in pyuff.UFF(sys.argv[1]).read_sets():
    if s["type"] == 58:
        data = np.asarray(s["data"])
        values = [[float(v.real), float(v.imag)] for v in data] if np.iscomplexobj(data) else [float(v) for v in data]
        out["functions"].append({
            "func_type": int(s["func_type"]),
            "rsp_node": int(s["rsp_node"]), "ref_node": int(s["ref_node"]),
            "rsp_dir": int(s["rsp_dir"]), "ref_dir": int(s["ref_dir"]),
            "ordinate_spec_data_type": int(s["ordinate_spec_data_type"]),
            "abscissa_inc": float(s["abscissa_inc"]),
            "values": values,
        })
    elif s["type"] == 151:
        out["headers"].append({k: s[k] for k in ("model_name", "description", "db_app", "program")})
    elif s["type"] == 2411:
        for label, x, y, z in zip(s["node_nums"], s["x"], s["y"], s["z"]):
            out["nodes"][str(int(label))] = [float(x), float(y), float(z)]
json.dump(out, sys.stdout)
