#!/usr/bin/env python3
"""The content hash of a metaplate dataset: what its committed rows hold, whenever and however they were written.

usage: .venv/bin/python scripts/dataset_hash.py RUN_DIR [RUN_DIR ...]

SHA-256 over the committed rows sorted by (ix, iy, actuator, kind), each row's columns but `measured_at` in schema
order as the Python repr of (name, value) pairs, `ir` as its list of values, read with pyarrow. The committed files
are those the journal lists (a compaction line supersedes the files it lists, a quarantine line removes its file).
Two runs of one recipe with one configuration and seed have the same content hash: CHANGELOG.md names the hashes of
the fixed-seed datasets and every deliberate change of them.
"""

import hashlib
import json
import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

CRC_FIELD = ',"crc32":"'


def committed_files(run: Path) -> list[Path]:
    live: list[str] = []
    for line in (run / "journal.jsonl").read_text().split("\n")[:-1]:
        at = line.rfind(CRC_FIELD)
        if at < 0:
            continue
        entry = json.loads(line[:at] + "}")
        if entry["kind"] in ("batch", "compaction"):
            live = [f for f in live if f not in entry.get("supersedes", [])] + [entry["file"]]
        elif entry["kind"] == "quarantine":
            live = [f for f in live if f != entry["file"]]
    return [run / "batches" / f for f in live]


def content_hash(run: Path) -> tuple[str, int]:
    table = pa.concat_tables([pq.read_table(f) for f in committed_files(run)], promote_options="default")
    names = [n for n in table.column_names if n != "measured_at"]
    rows = table.select(names).to_pylist()
    rows.sort(key=lambda r: (r["ix"], r["iy"], r["actuator"], r.get("kind") or ""))
    digest = hashlib.sha256()
    for row in rows:
        digest.update(repr([(n, row[n]) for n in names]).encode())
    return digest.hexdigest(), len(rows)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for arg in sys.argv[1:]:
        hexdigest, count = content_hash(Path(arg))
        print(f"{hexdigest}  {count} rows  {arg}")
