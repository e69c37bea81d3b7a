#!/usr/bin/env bash
# Builds the fuzz corpora in fuzz/corpus/<target>/ (not committed) from
#  - fuzz/regressions/<target>/: the small committed set (project-written
#    files, and any input a fuzzer found to fail);
#  - the real files of the repository: GreatSPN and MCC nets of
#    crates/petri/tests/data (third-party, kept there with their
#    provenance and licences), the maps and places of maps/, the suites'
#    scenarios, the topological map of crates/topo/tests/data;
#  - /work/shared/models and /work/shared/maps when present (the same
#    third-party files as read by the tests; copied into the corpus only,
#    never committed: see README.md).
# Usage: fuzz/seeds.sh   (from anywhere; existing corpus files are kept)
set -euo pipefail
cd "$(dirname "$0")"
repo=..
shared=${PETRINAV_SHARED:-/work/shared}

put() { # put TARGET FILE...
    local target=$1
    shift
    mkdir -p "corpus/$target"
    for f in "$@"; do
        [ -f "$f" ] && cp "$f" "corpus/$target/$(basename "$(dirname "$f")")_$(basename "$f")"
    done
    return 0
}

for d in regressions/*/; do
    put "$(basename "$d")" "$d"*
done
put pnpro "$repo"/crates/petri/tests/data/greatspn/*.PNPRO "$shared"/models/greatspn/*.PNPRO
put pnml "$repo"/crates/petri/tests/data/mcc/*.pnml "$shared"/models/mcc/*.pnml
put toml_net "$repo"/models/*.toml
put map_yaml "$repo"/maps/*/*.yaml "$shared"/maps/*/*.yaml
# building_31 only: levine (2048 × 2048) takes ~30 ms an input.
put map_image "$repo"/maps/building_31/*.png
put scenario "$repo"/crates/lab/src/suites/*/scenarios/*.toml "$repo"/crates/lab/src/suites/*/*.toml
put places "$repo"/maps/*/places.yaml
put fpn_map "$repo"/crates/topo/tests/data/*.json
# The bad-input corpus's logs and results (their net ids as placeholders:
# the fuzzer mutates them anyway).
put mission_log "$repo"/tests/bad_inputs/fixtures/*.jsonl
put results "$repo"/tests/bad_inputs/fixtures/voting/results.jsonl
# Expressions: the rates, weights and markings written in the model files.
mkdir -p corpus/expr
grep -ohE '(delay|weight|marking|mult|value)="[^"]+"' \
    "$repo"/crates/petri/tests/data/greatspn/*.PNPRO 2>/dev/null |
    sed -E 's/^[a-z]+="(.*)"$/\1/' | sort -u | head -40 |
    while IFS= read -r e; do
        printf '%s' "$e" >"corpus/expr/model_$(printf '%s' "$e" | cksum | cut -d' ' -f1)"
    done
for t in regressions/*/; do
    printf '%-12s %4d files\n' "$(basename "$t")" "$(ls "corpus/$(basename "$t")" | wc -l)"
done
