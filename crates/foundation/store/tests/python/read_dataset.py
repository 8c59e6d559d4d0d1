#!/usr/bin/env python3
"""Reads a metaplate dataset with polars and with pyarrow, without metaplate's code, and checks what it finds.

usage: read_dataset.py RUN_DIR EXPECTED.json

EXPECTED.json: {"rows": N, "ir_len": L, "point_index": P, "actuator": A, "ir_head": [first samples of that IR],
"file_metadata": {key: value}} (every batch file's key-value metadata; "metaplate.grid" compared as JSON).
The committed files are those the journal lists (journal.jsonl; each line's crc32 is zlib.crc32 of the line without
its crc32 field); a compaction line supersedes the files it lists, a quarantine line removes its file. Exits nonzero,
saying why, on any mismatch.
"""

import json
import sys
import zlib
from pathlib import Path

import polars as pl
import pyarrow as pa
import pyarrow.parquet as pq

CRC_FIELD = ',"crc32":"'
COLUMNS = {
    "point_index": (pl.UInt32, pa.uint32()),
    "ix": (pl.UInt32, pa.uint32()),
    "iy": (pl.UInt32, pa.uint32()),
    "x_m": (pl.Float64, pa.float64()),
    "y_m": (pl.Float64, pa.float64()),
    "actuator": (pl.UInt16, pa.uint16()),
    "sample_rate_hz": (pl.Float64, pa.float64()),
    "ir": (None, None),  # a fixed-size list of f32, its size the dataset's IR length: checked below
    "snr_db": (pl.Float64, pa.float64()),
    "status": (pl.String, pa.string()),
    "retries": (pl.UInt32, pa.uint32()),
    "measured_at": (pl.Datetime("us", "UTC"), pa.timestamp("us", tz="UTC")),
    "kind": (pl.String, pa.string()),
    "estimated_error_db": (pl.Float64, pa.float64()),
}


def committed_files(run: Path) -> list[Path]:
    live: list[str] = []
    for number, line in enumerate((run / "journal.jsonl").read_text().split("\n")[:-1], start=1):
        at = line.rfind(CRC_FIELD)
        body = line[:at] + "}"
        if at < 0 or int(line[at + len(CRC_FIELD):-2], 16) != zlib.crc32(body.encode()):
            print(f"journal line {number} damaged: skipped")
            continue
        entry = json.loads(body)
        if entry["kind"] in ("batch", "compaction"):
            live = [f for f in live if f not in entry.get("supersedes", [])] + [entry["file"]]
        elif entry["kind"] == "quarantine":
            live = [f for f in live if f != entry["file"]]
    return [run / "batches" / f for f in live]


def check(condition: bool, what: str) -> None:
    if not condition:
        sys.exit(f"MISMATCH: {what}")


def main() -> None:
    run, expected = Path(sys.argv[1]), json.loads(Path(sys.argv[2]).read_text())
    files = committed_files(run)
    check(len(files) > 0, "no committed files")

    df = pl.read_parquet([str(f) for f in files])
    check(df.height == expected["rows"], f"polars rows {df.height} != {expected['rows']}")
    check(df.columns == list(COLUMNS), f"polars columns {df.columns}")
    for name, (pl_type, _) in COLUMNS.items():
        if pl_type is None:
            pl_type = pl.Array(pl.Float32, expected["ir_len"])
        check(df.schema[name] == pl_type, f"polars {name} is {df.schema[name]}, expected {pl_type}")
    row = df.filter((pl.col("point_index") == expected["point_index"]) & (pl.col("actuator") == expected["actuator"]))
    check(row.height == 1, f"polars: {row.height} rows for the expected key")
    ir = row["ir"][0].to_list()
    check(len(ir) == expected["ir_len"], f"polars ir length {len(ir)}")
    check(ir[: len(expected["ir_head"])] == expected["ir_head"], f"polars ir head {ir[:4]} != {expected['ir_head'][:4]}")

    table = pa.concat_tables([pq.read_table(f) for f in files])
    check(table.num_rows == expected["rows"], f"pyarrow rows {table.num_rows}")
    check(table.column_names == list(COLUMNS), f"pyarrow columns {table.column_names}")
    for name, (_, pa_type) in COLUMNS.items():
        field = table.schema.field(name)
        if pa_type is None:
            check(
                pa.types.is_fixed_size_list(field.type)
                and field.type.value_type == pa.float32()
                and field.type.list_size == expected["ir_len"],
                f"pyarrow ir is {field.type}",
            )
        else:
            check(field.type == pa_type, f"pyarrow {name} is {field.type}, expected {pa_type}")
    check(table.schema.field("x_m").metadata.get(b"unit") == b"m", "pyarrow: x_m has no unit m")
    keys = list(zip(table["point_index"].to_pylist(), table["actuator"].to_pylist()))
    index = keys.index((expected["point_index"], expected["actuator"]))
    check(table["ir"][index].as_py()[: len(expected["ir_head"])] == expected["ir_head"], "pyarrow ir head")
    check(len(set(keys)) == len(keys), "duplicate (point, actuator) keys")
    # NumPy: the fixed-size list is a 2-D array, rows x samples.
    check(df["ir"].to_numpy().shape == (expected["rows"], expected["ir_len"]), "polars ir as NumPy is not 2-D")
    for f in files:
        found = {k.decode(): v.decode() for k, v in pq.read_metadata(f).metadata.items() if k.startswith(b"metaplate.")}
        polars_found = {k: v for k, v in pl.read_parquet_metadata(f).items() if k.startswith("metaplate.")}
        check(found == polars_found, f"{f.name}: polars and pyarrow disagree on the key-value metadata")
        for key, value in expected["file_metadata"].items():
            got = json.loads(found.get(key, "null")) if key == "metaplate.grid" else found.get(key)
            check(got == value, f"{f.name}: {key} is {got!r}, expected {value!r}")
    print(f"ok: {len(files)} files, {df.height} rows, read by polars {pl.__version__} and pyarrow {pa.__version__}")


if __name__ == "__main__":
    main()
