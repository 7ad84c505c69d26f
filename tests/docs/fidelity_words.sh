#!/usr/bin/env bash
# docs/fidelity-table.md (written by the fidelity test) is the one statement of what the HIL reproduces of the paper.
# README.md and docs/hil-model.md must quote it unchanged between their fidelity-table markers, and say nothing
# beyond it: every claim of agreement with the paper names its rows by id (`F8-...`, `F12-...`, `E12-...`), and a row
# named in a claim that it agrees must be marked so in the table (within 25 %, and for an effect the paper's
# direction), one named in a claim that it does not must not be. A claim of agreement is a sentence that says
# "reproduc...", or that says "match...", "agree...", "within", "near...", "close to" or "consistent" and speaks of the
# paper (or of Fig. 8 or Fig. 12). Headings, link targets, words in double quotes (the paper's, or a word named) and
# sentences that point at docs/fidelity-table.md itself are not claims. Every row of the table says its kind (direct,
# derived, inferred, variant or effect; docs/hil-model.md, "Fidelity to the paper").
# usage: fidelity_words.sh SOURCE_DIR [FILE...]   (FILE: the documents to check; default README.md docs/hil-model.md)
set -euo pipefail
root=$1
shift
(($#)) || set -- "$root/README.md" "$root/docs/hil-model.md"
python3 - "$root/docs/fidelity-table.md" "$@" <<'PY'
import re, sys
table_path, docs = sys.argv[1], sys.argv[2:]
body = "".join(l for l in open(table_path) if not l.startswith("<!--"))
rows = {}
for line in body.splitlines():
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    m = re.fullmatch(r"`([A-Za-z0-9.-]+)`", cells[0]) if cells else None
    if m and len(cells) == 8:
        within, direction, kind = cells[5], cells[6], cells[7]
        if kind not in ("direct", "derived", "inferred", "variant", "effect"):
            sys.exit(f"{table_path}: row `{m.group(1)}` has no kind (direct, derived, inferred, variant, effect): '{kind}'")
        rows[m.group(1)] = within != "no" and direction != "no" and (within, direction) != ("-", "-")
if len(rows) < 10:
    sys.exit(f"{table_path}: only {len(rows)} rows read")
failures = []
for doc in docs:
    text = open(doc).read()
    begin, end = "<!-- fidelity-table:begin -->\n", "<!-- fidelity-table:end -->"
    if text.count(begin) != 1 or text.count(end) != 1:
        failures.append(f"{doc}: no single fidelity-table block")
        continue
    a, b = text.index(begin) + len(begin), text.index(end)
    if text[a:b] != body:
        failures.append(f"{doc}: its fidelity table is not docs/fidelity-table.md's (hil/experiments/fidelity-table)")
    prose = text[: a - len(begin)] + text[b + len(end):]
    prose = "\n".join(l for l in prose.splitlines() if not l.lstrip().startswith(("#", "|", "<!--")))
    prose = re.sub(r"\]\([^)]*\)", "]", prose)   # link targets
    prose = re.sub(r'"[^"\n]*"', '""', prose)     # quoted words
    for sentence in re.split(r"(?<=[.;:!?])\s+|\n\s*\n|\n\s*[-*] ", prose):
        if not re.search(r"reproduc", sentence, re.I) and not (
            re.search(r"\bmatch|\bagree|\bwithin\b|\bnear(?:er|est)?\b|\bclose to\b|\bconsistent", sentence, re.I)
            and re.search(r"\bpaper|\bFig\. ?(8|12)\b", sentence)):
            continue
        one_line = " ".join(sentence.split())
        if "fidelity-table" in sentence:  # points at the table itself
            continue
        ids = re.findall(r"`((?:F8|F12|E12)-[A-Za-z0-9.-]+)`", sentence)
        if not ids:
            failures.append(f'{doc}: "{one_line[:140]}" claims agreement with the paper without naming a row of the table')
            continue
        negative = re.search(r"\b(not|no)\b[^.]*(reproduc|match|agree|within|near|close to|consistent)|never|cannot|n't|"
                             r"\bfar from\b|\bshort of\b|\bfalls? short\b", sentence, re.I)
        for i in ids:
            if i not in rows:
                failures.append(f"{doc}: `{i}` is not a row of the table")
            elif rows[i] == bool(negative):
                verdict = "reproduced" if rows[i] else "not reproduced"
                failures.append(f'{doc}: "{one_line[:140]}" contradicts the table, where `{i}` is {verdict}')
for f in failures:
    print(f, file=sys.stderr)
if failures:
    sys.exit(1)
print(f"{', '.join(docs)}: the fidelity table quoted unchanged, every claim of agreement with the paper as the table says")
PY
