#!/usr/bin/env bash
# The runner of the documented long blocks can fail: on fake pages, a failing
# long block, missing stand-ins, an interactive program that exits or prints
# an error, a block whose line moved and (in the suite's own check) a script
# run as a program without its x bit are each refused; good blocks pass.
#   documented_runner_fails.sh <documented_commands.py>
set -euo pipefail
runner="$1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
src="$work/src" build="$work/build"
mkdir -p "$src/docs" "$src/data" "$build"
cat >"$src/README.md" <<'PAGE'
<!-- tested: integration.documented_commands -->
```sh
echo first steps > first.txt
```
PAGE
cat >"$src/docs/page.md" <<'PAGE'
<!-- long: passes -->
```sh
grep -q "first steps" first.txt && test -f data/.keep
```

<!-- long: fails -->
```sh
false
```

<!-- template: mine.txt stands for a file of yours -->
```sh
grep -q stand-in mine.txt
```

<!-- interactive: stays open -->
```sh
sleep 60
```

<!-- interactive: exits at once -->
```sh
true
```

<!-- interactive: prints an error -->
```sh
echo "viewer: error: no such bake"; sleep 60
```
PAGE
touch "$src/data/.keep"
py() { PRT_DOCS_QUIET_SECONDS=2 DISPLAY=:fake /usr/bin/python3 "$runner" "$@"; }
line() { awk -v m="$1" 'index($0, m) { f = 1 } f && /^```sh$/ { print NR; exit }' "$src/docs/page.md"; }
py --list "$src" | tee "$work/list"
[ "$(wc -l <"$work/list")" = 6 ] || { echo "FAIL: --list found $(wc -l <"$work/list") blocks, not 6"; exit 1; }
mkdir -p "$src/scripts" && touch "$src/scripts/build.sh"  # not a top-level build folder
py --setup true "$build" "$src" >/dev/null
[ -f "$build/docs-long/checkout/scripts/build.sh" ] || { echo "FAIL: the copy lost scripts/build.sh"; exit 1; }
expect() {  # pass|fail WHY -> runs that block
  local want=$1 block="docs/page.md:$(line "$2")"
  if py --run "$block" true "$build" "$src" >"$work/out" 2>&1; then got=pass; else got=fail; fi
  [ "$got" = "$want" ] || { cat "$work/out"; echo "FAIL: $block ($2) should $want"; exit 1; }
  echo "$block ($2): ${got}ed, as it should"
}
expect pass "long: passes"
expect fail "long: fails"
expect fail "template: mine.txt"  # no stand-ins for the page
grep -q "needs stand-ins" "$work/out" || { cat "$work/out"; echo "FAIL: no stand-ins not named"; exit 1; }
mkdir -p "$src/tests/integration/doc_standins/page"
expect fail "template: mine.txt"  # no mine.txt among them
echo "a stand-in" >"$src/tests/integration/doc_standins/page/mine.txt"
ln -s mine.txt "$src/tests/integration/doc_standins/page/link.txt"
expect pass "template: mine.txt"
expect pass "template: mine.txt"  # again, over the stand-ins (a link too) it copied
expect pass "interactive: stays open"
expect fail "interactive: exits at once"
expect fail "interactive: prints an error"
if py --run docs/page.md:3 true "$build" "$src" >"$work/out" 2>&1 || ! grep -q "no long, template" "$work/out"; then
  cat "$work/out"; echo "FAIL: a line where no block starts is not refused"; exit 1
fi
# The suite's own check: a script a long block runs as a program must be executable.
printf '<!-- long: a tool -->\n```sh\nscripts/tool.sh\n```\n' >>"$src/docs/page.md"
printf '#!/bin/sh\n' >"$src/scripts/tool.sh"
if py true "$build" "$src" >"$work/out" 2>&1 || ! grep -q "scripts/tool.sh is not executable" "$work/out"; then
  cat "$work/out"; echo "FAIL: a script without its x bit is not refused"; exit 1
fi
chmod +x "$src/scripts/tool.sh"
py true "$build" "$src" >"$work/out" 2>&1 || { cat "$work/out"; echo "FAIL: good pages refused"; exit 1; }
echo "documented blocks' runner: fails where it should"
