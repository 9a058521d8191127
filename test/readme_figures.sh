#!/usr/bin/env bash
# test/readme_figures.sh -- README.md quotes only measured figures, and no history.
#
# 1. Every number in the README's "Performance" section (its tables and its
#    prose) appears, as the same digits, in one of the reports that the
#    benchmarks write under docs/benchmarks/ (bench_publish in bench/lib.sh):
#    a figure copied by hand, or left over from an older run, fails.
# 2. Every report the README links to under docs/benchmarks/ exists.
# 3. The README has no ISO date, no clock time, no commit hash, and does not
#    mention issues: its reader has no tracker, and dates belong to
#    CHANGELOG.md and to the reports' headers.
# Prints one line per failure and ends with "N passed, N failed".
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
README=${README:-$ROOT/README.md}
REPORTS=${REPORTS:-$ROOT/docs/benchmarks}
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); printf 'FAIL: %s\n' "$*"; }

# the Performance section: from its heading to the next heading of level 2
perf=$(awk '/^## / { on = ($0 ~ /^## Performance/) } on' "$README")
if [ -z "$perf" ]; then
	bad "README.md has no '## Performance' section"
fi

# the numbers of all reports, normalised (thousands separators dropped), one a line
report_numbers=$(cat "$REPORTS"/*.md 2>/dev/null | grep -oE '[0-9][0-9,]*(\.[0-9]+)?' | tr -d , | sort -u)
[ -n "$report_numbers" ] || bad "no report with figures in $REPORTS"

# 1. each figure of the section, but not the link targets and code spans,
#    which name files and functions rather than quote measurements
figures=$(printf '%s\n' "$perf" | sed -E 's/\]\([^)]*\)/]/g; s/`[^`]*`//g' |
	grep -oE '[0-9][0-9,]*(\.[0-9]+)?' | tr -d , | sort -u)
nfig=0
for f in $figures; do
	nfig=$((nfig + 1))
	if grep -qxF -- "$f" <<< "$report_numbers"; then
		ok
	else
		bad "README's Performance section quotes $f, which no docs/benchmarks/*.md holds"
	fi
done
[ "$nfig" -gt 0 ] || bad "README's Performance section quotes no figure"

# 2. the linked reports exist
links=$(grep -oE 'docs/benchmarks/[A-Za-z0-9_.-]+\.md' "$README" | sort -u)
[ -n "$links" ] || bad "README.md links to no report under docs/benchmarks/"
for l in $links; do
	if [ -s "$ROOT/$l" ]; then ok; else bad "README.md links to $l, which does not exist"; fi
done

# 3. no dates, times, hashes or issues anywhere in the README
check_absent() {	# WHAT REGEX
	local hits
	hits=$(grep -nE -- "$2" "$README" | head -5)
	if [ -z "$hits" ]; then ok; else bad "README.md has $1: $(printf '%s' "$hits" | tr '\n' ' ' | cut -c1-300)"; fi
}
check_absent "an ISO date" '(^|[^0-9])(19|20)[0-9]{2}-[01][0-9]-[0-3][0-9]([^0-9]|$)'
check_absent "a clock time" '(^|[^0-9:])([01]?[0-9]|2[0-3]):[0-5][0-9]([^0-9]|$)'
# a hash: 7 to 40 hex digits standing alone, with at least one digit and one letter
hashes=$(grep -noE '(^|[^0-9A-Za-z_.-])[0-9a-f]{7,40}([^0-9A-Za-z_]|$)' "$README" |
	awk -F: '{ t = $2; gsub(/[^0-9a-f]/, "", t); if (t ~ /[0-9]/ && t ~ /[a-f]/) print $1 ": " t }' | head -5)
if [ -z "$hashes" ]; then ok; else bad "README.md has a commit hash: $(printf '%s' "$hashes" | tr '\n' ' ')"; fi
check_absent "a mention of an issue" '(^|[^A-Za-z])[Ii]ssues?([^A-Za-z]|$)'

echo "readme_figures: $nfig figures in the Performance section"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
