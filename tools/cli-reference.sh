#!/usr/bin/env bash
# Prints docs/cli.md, the command-line reference, from the commands' own --help:
#   bash tools/cli-reference.sh build/tools/driftlab/driftlab > docs/cli.md
# Every subcommand is found in its parent's "Subcommands:" list and printed in that order.
# tests/tools/docs_test.cpp runs this script and compares its output with docs/cli.md.
set -euo pipefail
exe=${1:?usage: bash tools/cli-reference.sh PATH/TO/driftlab}

subcommands() {  # the names listed under "Subcommands:" in a help text
  awk '/^Subcommands:/ {in_list = 1; next} in_list && /^  [a-z]/ {print $1} in_list && /^[^ ]/ {in_list = 0}'
}

section() {  # section LEVEL WORDS...: the help of `driftlab WORDS... --help`, then its subcommands'
  local level=$1
  shift
  local help
  help=$("$exe" "$@" --help)
  local title="driftlab${*:+ $*}"
  printf '\n%s `%s`\n\n```text\n%s\n```\n' "$(printf '#%.0s' $(seq "$level"))" "$title" "$help"
  local sub
  for sub in $(subcommands <<<"$help"); do
    section $((level + 1)) "$@" "$sub"
  done
}

echo '# Command-line reference'
echo
echo 'Generated from the commands'"'"' own `--help` by `bash tools/cli-reference.sh build/tools/driftlab/driftlab >'
echo 'docs/cli.md`; a test (`Docs.CliReferenceIsWhatTheCommandsPrint`) checks that it is current.'
echo 'Exit codes, shared data options and what each command writes: [usage.md](usage.md).'
section 2
