#!/usr/bin/env bash
# Times README's demo command as a new user meets it: a bare Debian 12 root
# (debootstrap minbase), a fresh clone of this repository, `bash
# scripts/demo.sh` inside it (apt, data, configure, build, bake, render).
# Needs root, network and debootstrap (apt-get install debootstrap).
#   sudo bash scripts/time_fresh_demo.sh [ROOT_FOLDER]   (default /tmp/prt-fresh-root)
# Prints the total and the apt share; leaves the root for inspection
# (remove it with: umount ROOT/proc ROOT/dev; rm -rf ROOT).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
root="${1:-/tmp/prt-fresh-root}"
[ "$(id -u)" -eq 0 ] || { echo "time_fresh_demo: run as root (chroot, mount)" >&2; exit 2; }
command -v debootstrap >/dev/null || { echo "time_fresh_demo: apt-get install debootstrap" >&2; exit 2; }
[ ! -e "$root" ] || { echo "time_fresh_demo: $root exists; remove it or name another" >&2; exit 2; }
debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >/dev/null
cp /etc/resolv.conf "$root/etc/resolv.conf"
mount -t proc proc "$root/proc"
mount --bind /dev "$root/dev"
git clone -q "$repo" "$root/root/prt"
chroot "$root" /bin/bash -c '
  cd /root/prt
  start=$(date +%s)
  DEBIAN_FRONTEND=noninteractive bash scripts/demo.sh >/root/demo.log 2>&1 || { tail -n 20 /root/demo.log; exit 1; }
  end=$(date +%s)
  echo "demo: $((end - start)) s from a bare Debian 12 root to $(ls out/bunny.png) (log: /root/demo.log)"
  grep -E "^(Start|End)-Date" /var/log/apt/history.log | sed "s/^/apt /"'
