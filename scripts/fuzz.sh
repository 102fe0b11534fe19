#!/usr/bin/env bash
# Coverage-guided fuzzing of the readers and parsers with AFL++ on stable
# Rust (cargo-afl).
#
#   scripts/fuzz.sh [target|all] [executions]
#
# Targets are the functions of crates/mp-fuzz (`scripts/fuzz.sh list` names
# them); the default is every target, one after the other, for 1,000,000
# executions each. Seeds come from crates/mp-fuzz/corpus/<target>/, results
# go to fuzz/out/<target>/ (a second run resumes there). Environment:
#   FUZZ_SECONDS=N   stop each target after N seconds, or at the count when
#                    one is given too (whichever comes first)
#   FUZZ_NICE=N      niceness of the fuzzer (default 19)
# Time every input of a queue in process (the slowest first):
#   cargo run --release -p mp-fuzz --example replay -- <target> fuzz/out/<target>/default/queue
# Crashes land in fuzz/out/<target>/default/crashes/; replay one with
#   fuzz/target/release/<target> < fuzz/out/<target>/default/crashes/<file>
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

targets=(concrete_dsl abstract_dsl program_json abstract_json grammar_json grammar_text
    npz npy csv json_track openpose bvh mpt mpb concepts_json people)

what="${1:-all}"
execs="${2:-}"
if [[ "$what" == "list" ]]; then
    printf '%s\n' "${targets[@]}"
    exit 0
fi
if [[ "$what" != "all" ]]; then
    found=0
    for t in "${targets[@]}"; do [[ "$t" == "$what" ]] && found=1; done
    if [[ $found -eq 0 ]]; then
        echo "unknown target \`$what\` (scripts/fuzz.sh list)" >&2
        exit 2
    fi
    targets=("$what")
fi

# Tools: cargo-afl, then AFL++ itself (built once with gcc/make).
if ! cargo afl --version >/dev/null 2>&1; then
    cargo install --locked cargo-afl
fi
afl_data="${XDG_DATA_HOME:-$HOME/.local/share}/afl.rs"
if ! compgen -G "$afl_data/rustc-*/afl.rs-*/afl/bin/afl-fuzz" >/dev/null; then
    cargo afl config --build
fi

# The instrumented build has its own target folder (fuzz/target).
(cd fuzz && cargo afl build --release)

for t in "${targets[@]}"; do
    out="fuzz/out/$t"
    mkdir -p "$out"
    limit=()
    [[ -n "${FUZZ_SECONDS:-}" ]] && limit+=(-V "$FUZZ_SECONDS")
    [[ -n "$execs" || ${#limit[@]} -eq 0 ]] && limit+=(-E "${execs:-1000000}")
    echo "== $t: ${limit[*]}"
    start=$(date +%s)
    # AFL's exit status is not the target's: crashes are counted below.
    nice -n "${FUZZ_NICE:-19}" env AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1 \
        AFL_AUTORESUME=1 AFL_NO_UI=1 AFL_NO_AFFINITY=1 \
        cargo afl fuzz -i "crates/mp-fuzz/corpus/$t" -o "$out" "${limit[@]}" \
        -- "fuzz/target/release/$t" >"$out/afl.log" 2>&1 || true
    stats="$out/default/fuzzer_stats"
    if [[ -f "$stats" ]]; then
        get() { awk -F' *: *' -v k="$1" '$1 == k { print $2 }' "$stats"; }
        echo "   executions $(get execs_done), $(get execs_per_sec)/s, corpus $(get corpus_count)," \
            "crashes $(get saved_crashes), hangs $(get saved_hangs), $(($(date +%s) - start)) s"
    else
        echo "   no fuzzer_stats; see $out/afl.log" >&2
        tail -20 "$out/afl.log" >&2
    fi
done
