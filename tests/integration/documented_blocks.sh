# Sourced by the tests that run a document's commands verbatim
# (out_of_tree.sh, python_install.sh).
#
# scratch_checkout BUILD SRC: sets $work to a new folder (removed on exit)
# holding home/ and checkout/, a checkout that shares BUILD (build ->) and has
# SRC's examples and scenes copied and data linked.
scratch_checkout() {
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
  mkdir -p "$work/home" "$work/checkout"
  ln -s "$1" "$work/checkout/build"
  cp -r "$2/examples" "$2/scenes" "$work/checkout/"
  ln -s "$2/data" "$work/checkout/data"
}

# tested_blocks DOC: prints the ```sh blocks of DOC that follow a
# "<!-- tested: ... -->" marker, in order.
tested_blocks() {
  awk '/<!-- tested:/ { want = 1; next }
       want && /^```sh$/ { inside = 1; next }
       inside && /^```$/ { inside = 0; want = 0; next }
       inside { print }' "$1"
}
