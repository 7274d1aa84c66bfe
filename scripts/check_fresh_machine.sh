#!/usr/bin/env bash
# The release check: the README's two commands on a machine that has nothing but a
# minimal Debian 12.
#
#   sudo scripts/check_fresh_machine.sh [--cache DIR] [--keep] [--only demo|test]
#
# 1. A minimal Debian 12 (bookworm) root made by debootstrap --variant=minbase, cached as a
#    tarball in the cache folder (default /var/cache/weft-fresh-machine, or
#    $WEFT_FRESH_CACHE) and reused when present. Every run unpacks it anew, so each run
#    starts from the same fresh root; the .deb files apt downloads are kept in the cache
#    (cache/apt-archives) so that a second run installs them again without the download.
# 2. The working tree (tracked and untracked files that git does not ignore, so no build/)
#    goes to /work/weft inside the root and ../shared beside it, as /work/shared.
# 3. scripts/demo.sh, then scripts/test.sh, run inside it with chroot, with /proc, /sys,
#    /dev and a tmpfs /tmp mounted. Each command's wall time is printed. --only runs one of
#    the two (the test command alone checks the build and its packages in ~20 min).
# Exits non-zero when either command fails. Every mount is undone on every exit path
# (normal end, failure, Ctrl-C, SIGTERM), and the unpacked root is removed unless --keep.
# Apt inside the root uses this machine's apt sources and Acquire settings.
set -euo pipefail
trap 'echo "check_fresh_machine: failed at line $LINENO: $BASH_COMMAND" >&2' ERR

cache=${WEFT_FRESH_CACHE:-/var/cache/weft-fresh-machine}
keep=0
only=""
while (($#)); do
  case "$1" in
    --cache) cache=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --only)
      [ "${2:-}" = demo ] || [ "${2:-}" = test ] ||
        { echo "check_fresh_machine: --only takes demo or test, not '${2:-}'" >&2; exit 2; }
      only=$2; shift 2 ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    *) echo "check_fresh_machine: unknown argument '$1' (expected --cache DIR, --keep or --only demo|test)" >&2; exit 2 ;;
  esac
done

if [ "$(id -u)" != 0 ]; then
  echo "check_fresh_machine: needs root (debootstrap, chroot and mount): run it with sudo" >&2
  exit 2
fi
src=$(cd "$(dirname "$0")/.." && pwd)
shared=$(cd "$src/.." && pwd)/shared
[ -d "$shared" ] || { echo "check_fresh_machine: $shared is missing (the tests read ../shared beside the tree)" >&2; exit 2; }
command -v debootstrap >/dev/null || {
  echo "check_fresh_machine: installing debootstrap"
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap; } \
    >/dev/null
}

# This machine's Debian mirror, read from its apt sources (deb822 or one-line form).
mirror=$(
  { cat /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '/^URIs:/ {print $2}';
    cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
      awk '/^deb / { for (i = 2; i <= NF; ++i) if ($i ~ /^[a-z]+:\/\//) { print $i; break } }'; } |
    grep -v -- '-security' | head -n 1 || true
)
[ -n "$mirror" ] || { echo "check_fresh_machine: no Debian mirror found in /etc/apt/sources.list{,.d}" >&2; exit 2; }

mkdir -p "$cache/apt-archives/partial"
tarball=$cache/debian12-minbase.tar
root=""
mounts=()

# Undo every mount (innermost first), end whatever still runs inside the root, and
# remove the unpacked root. Runs on every exit path.
cleanup() {
  local status=$?
  trap - EXIT INT TERM
  if [ -n "$root" ] && [ -d "$root" ]; then
    local pid
    for pid in $(ls /proc | grep -E '^[0-9]+$'); do
      [ "$(readlink "/proc/$pid/root" 2>/dev/null)" = "$root" ] && kill -KILL "$pid" 2>/dev/null || true
    done
    local i
    for ((i = ${#mounts[@]} - 1; i >= 0; i--)); do
      umount -R "${mounts[i]}" 2>/dev/null || umount -l -R "${mounts[i]}" 2>/dev/null || true
    done
    if grep -q " $root" /proc/mounts; then
      echo "check_fresh_machine: mounts left under $root:" >&2
      grep " $root" /proc/mounts >&2
      status=1
    elif ((keep)); then
      echo "check_fresh_machine: the root is kept at $root"
    else
      rm -rf --one-file-system "$root"
    fi
  fi
  exit "$status"
}
trap cleanup EXIT
trap 'echo "check_fresh_machine: interrupted" >&2; exit 130' INT
trap 'echo "check_fresh_machine: terminated" >&2; exit 143' TERM

now() { date +%s.%N; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { s = b - a; printf "%d min %04.1f s", s / 60, s - 60 * int(s / 60) }'; }

if [ ! -f "$tarball" ]; then
  echo "check_fresh_machine: making a minimal Debian 12 root (debootstrap, once; cached in $tarball)"
  t0=$(now)
  boot=$(mktemp -d "$cache/debootstrap.XXXXXX")
  root=$boot  # so that an interrupt removes the half-made root
  debootstrap --variant=minbase --cache-dir="$cache/apt-archives" bookworm "$boot" "$mirror" >"$cache/debootstrap.log" 2>&1 ||
    { echo "check_fresh_machine: debootstrap failed; see $cache/debootstrap.log" >&2; exit 1; }
  tar -C "$boot" -cf "$tarball.tmp" . && mv "$tarball.tmp" "$tarball"
  rm -rf --one-file-system "$boot"
  root=""
  echo "check_fresh_machine: debootstrap took $(seconds "$t0" "$(now)")"
else
  echo "check_fresh_machine: reusing the cached root $tarball"
fi

root=$(mktemp -d "$cache/root.XXXXXX")
tar -C "$root" -xf "$tarball"
# Apt as set up on this machine: its sources and its Acquire settings.
rm -f "$root/etc/apt/sources.list"
cp -a /etc/apt/sources.list.d/. "$root/etc/apt/sources.list.d/" 2>/dev/null || true
[ -f /etc/apt/sources.list ] && cp /etc/apt/sources.list "$root/etc/apt/sources.list"
for f in /etc/apt/apt.conf.d/*; do
  grep -q '^Acquire::' "$f" 2>/dev/null && cp "$f" "$root/etc/apt/apt.conf.d/"
done
# Keep downloaded packages (the cache below) instead of deleting them after install.
rm -f "$root/etc/apt/apt.conf.d/docker-clean"
echo 'Binary::apt::APT::Keep-Downloaded-Packages "true";' >"$root/etc/apt/apt.conf.d/10keep-downloads"
cp /etc/resolv.conf "$root/etc/resolv.conf"

mkdir -p "$root/work/weft" "$root/work/shared"
(cd "$src" && git ls-files -co --exclude-standard -z | tar --null -T - -cf -) | tar -C "$root/work/weft" -xf -
cp -a "$shared/." "$root/work/shared/"

mount_into() {  # mount_into TARGET MOUNT-ARGS...
  local target=$root$1
  shift
  mkdir -p "$target"
  mount "$@" "$target"
  mounts+=("$target")
}
mount_into /proc -t proc proc
mount_into /sys --rbind /sys
mount --make-rslave "$root/sys"
mount_into /dev --rbind /dev
mount --make-rslave "$root/dev"
mount_into /tmp -t tmpfs -o size=8g tmpfs
mount_into /var/cache/apt/archives --bind "$cache/apt-archives"

# run_inside NAME COMMAND: runs COMMAND in the root's work tree with a clean environment.
failed=0
run_inside() {
  local name=$1 cmd=$2 t0 status=0
  echo "check_fresh_machine: $name (log: $cache/$name.log)"
  t0=$(now)
  chroot "$root" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    LANG=C.UTF-8 TERM=dumb /bin/bash -c "cd /work/weft && $cmd" >"$cache/$name.log" 2>&1 || status=$?
  local took
  took=$(seconds "$t0" "$(now)")
  if ((status)); then
    echo "check_fresh_machine: $name FAILED (exit $status) after $took; the end of its log:"
    tail -n 30 "$cache/$name.log"
    failed=1
  else
    echo "check_fresh_machine: $name passed in $took"
    tail -n 3 "$cache/$name.log"
  fi
}
[ "$only" = test ] || run_inside demo scripts/demo.sh
[ "$only" = demo ] || run_inside test scripts/test.sh
exit "$failed"
