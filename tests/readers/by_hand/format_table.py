"""The readers' rows (reader, call, label, result; TSV) as one Markdown table a reader.

Usage: format_table.py ROWS.tsv [ROWS.tsv ...]
A column a label, in the order the labels first appear; a call a row, in its first order.
"""
import csv
import sys


def main(paths):
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            rows += list(csv.DictReader(f, delimiter="\t", quoting=csv.QUOTE_NONE))
    readers = list(dict.fromkeys(r["reader"] for r in rows))
    for reader in readers:
        mine = [r for r in rows if r["reader"] == reader]
        labels = list(dict.fromkeys(r["label"] for r in mine))
        calls = list(dict.fromkeys(r["call"] for r in mine))
        cell = {(r["call"], r["label"]): r["result"].replace("|", "\\|") for r in mine}
        works = {label: sum(cell.get((c, label)) == "works" for c in calls) for label in labels}
        print(f"**{reader}** ({len(calls)} calls; works: "
              + ", ".join(f"{label} {works[label]}" for label in labels) + ")\n")
        print("| call | " + " | ".join(labels) + " |")
        print("|---" * (len(labels) + 1) + "|")
        for call in calls:
            print(f"| `{call}` | " + " | ".join(cell.get((call, label), "not run")
                                                  for label in labels) + " |")
        print()


if __name__ == "__main__":
    main(sys.argv[1:])
