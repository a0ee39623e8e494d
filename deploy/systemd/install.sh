#!/bin/sh
# Install or upgrade Inbetrieb as a systemd service, as root, from this checkout:
#   - a venv in /opt/inbetrieb with the package (pip; versions pinned by constraints.txt),
#     the built HMI in /opt/inbetrieb/share/frontend, the exercises in .../share/exercises;
#   - the system user `inbetrieb`, its store in /var/lib/inbetrieb;
#   - /etc/inbetrieb/inbetrieb.env with the common settings commented out (written once: an
#     upgrade never touches it);
#   - the unit in /etc/systemd/system/inbetrieb.service, then `systemctl daemon-reload`.
# An upgrade is the same command again (then `systemctl restart inbetrieb`).
#
#   make frontend && sudo deploy/systemd/install.sh
#   sudo deploy/systemd/install.sh --wheelhouse var/image/context/wheelhouse   # offline
#
# Options (or the variables in capitals):
#   --root DIR        install under DIR instead of / (ROOT; a package build or a test): no
#                     user is made, nothing is chowned or compiled, systemctl is not told
#   --python PY       the Python 3.11+ that makes the venv (PYTHON, default python3)
#   --wheelhouse DIR  install offline from DIR's wheels (WHEELHOUSE; `make image-context`
#                     makes one with its constraints.txt): --no-index --find-links DIR
#   --extras LIST     the package's extras, e.g. cluster for Ray (EXTRAS)
#   --editable        install the checkout editable (EDITABLE=1): a development box
#   --no-user         make no system user, chown nothing (CREATE_USER=0)
#   --no-warmup       do not compile the kernel into the service's cache now (WARMUP=0)
#   --frontend DIR    the built HMI (FRONTEND, default frontend/dist; `make frontend`)
# Extra arguments for `python -m venv` and `pip install`: VENV_ARGS, PIP_ARGS.
set -eu

SRC=$(CDPATH='' cd -- "$(dirname -- "$0")/../.." && pwd)
ROOT=${ROOT:-}
PYTHON=${PYTHON:-python3}
WHEELHOUSE=${WHEELHOUSE:-}
EXTRAS=${EXTRAS:-}
EDITABLE=${EDITABLE:-0}
CREATE_USER=${CREATE_USER:-}
WARMUP=${WARMUP:-}
FRONTEND=${FRONTEND:-$SRC/frontend/dist}
EXERCISES=${EXERCISES:-$SRC/exercises}
VENV_ARGS=${VENV_ARGS:-}
PIP_ARGS=${PIP_ARGS:-}

die() { echo "install.sh: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
    case $1 in
        --root) ROOT=${2:?--root DIR}; shift ;;
        --python) PYTHON=${2:?--python PY}; shift ;;
        --wheelhouse) WHEELHOUSE=${2:?--wheelhouse DIR}; shift ;;
        --extras) EXTRAS=${2:?--extras LIST}; shift ;;
        --frontend) FRONTEND=${2:?--frontend DIR}; shift ;;
        --editable) EDITABLE=1 ;;
        --no-user) CREATE_USER=0 ;;
        --no-warmup) WARMUP=0 ;;
        -h|--help) sed -n '2,/^set -eu/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'; exit 0 ;;
        *) die "unknown option $1 (--help lists them)" ;;
    esac
    shift
done
ROOT=${ROOT%/}
# for real (no --root): a user, and the kernel compiled where the service will look for it
[ -n "$CREATE_USER" ] || { [ -z "$ROOT" ] && CREATE_USER=1 || CREATE_USER=0; }
[ -n "$WARMUP" ] || { [ -z "$ROOT" ] && WARMUP=1 || WARMUP=0; }

OPT=$ROOT/opt/inbetrieb
ETC=$ROOT/etc/inbetrieb
STATE=$ROOT/var/lib/inbetrieb
CACHE=$ROOT/var/cache/inbetrieb
UNIT_DIR=$ROOT/etc/systemd/system
USER_NAME=inbetrieb

[ -f "$FRONTEND/index.html" ] || die "no built HMI in $FRONTEND: run \`make frontend\` first"
[ -d "$EXERCISES" ] || die "no exercises in $EXERCISES"
if [ "$CREATE_USER" = 1 ] && [ "$(id -u)" != 0 ]; then
    die "run as root (or with --root DIR --no-user for a staging tree)"
fi

# --- the venv: made once, made again when its Python is gone (the system's was upgraded) ---
if ! "$OPT/bin/python" -c '' 2>/dev/null; then
    echo "making the venv $OPT"
    # shellcheck disable=SC2086  # VENV_ARGS are words
    "$PYTHON" -m venv --clear $VENV_ARGS "$OPT"
fi
"$OPT/bin/python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
    || die "$OPT has a Python older than 3.11: remove it, give --python"

# --- the package: its dependencies as pinned, then the package itself always anew (an
# upgrade of the same version number brings the new code too) ---
SPEC=inbetrieb${EXTRAS:+[$EXTRAS]}
if [ -n "$WHEELHOUSE" ]; then
    [ -f "$WHEELHOUSE/constraints.txt" ] || die "no constraints.txt in $WHEELHOUSE"
    set -- --no-index --find-links "$WHEELHOUSE" -c "$WHEELHOUSE/constraints.txt" "$SPEC"
elif [ "$EDITABLE" = 1 ]; then
    set -- -c "$SRC/constraints.txt" -e "$SRC${EXTRAS:+[$EXTRAS]}"
else
    set -- -c "$SRC/constraints.txt" "$SRC${EXTRAS:+[$EXTRAS]}"
fi
echo "installing $SPEC into $OPT"
# shellcheck disable=SC2086  # PIP_ARGS are words
"$OPT/bin/python" -m pip install --quiet --disable-pip-version-check $PIP_ARGS "$@"
if [ "$EDITABLE" != 1 ]; then
    # shellcheck disable=SC2086
    "$OPT/bin/python" -m pip install --quiet --disable-pip-version-check $PIP_ARGS \
        --no-deps --force-reinstall "$@"
fi

# --- what the package does not carry: the HMI and the exercises (replaced whole) ---
mkdir -p "$OPT/share"
rm -rf "$OPT/share/frontend.new" "$OPT/share/exercises.new"
cp -R "$FRONTEND" "$OPT/share/frontend.new"
cp -R "$EXERCISES" "$OPT/share/exercises.new"
rm -rf "$OPT/share/frontend" "$OPT/share/exercises"
mv "$OPT/share/frontend.new" "$OPT/share/frontend"
mv "$OPT/share/exercises.new" "$OPT/share/exercises"

# --- the user, the store, the settings ---
if [ "$CREATE_USER" = 1 ] && ! id "$USER_NAME" >/dev/null 2>&1; then
    echo "adding the system user $USER_NAME"
    useradd --system --user-group --home-dir /var/lib/inbetrieb --no-create-home \
        --shell /usr/sbin/nologin --comment "Inbetrieb service" "$USER_NAME"
fi
mkdir -p "$STATE" "$ETC" "$CACHE"
chmod 0750 "$STATE"
if [ ! -e "$ETC/inbetrieb.env" ]; then
    echo "writing $ETC/inbetrieb.env (edit it, then systemctl restart inbetrieb)"
    umask 027
    cat >"$ETC/inbetrieb.env" <<'EOF'
# Settings of the Inbetrieb service: INBETRIEB_<SETTING>=value, one a line (backend/settings.py
# or `inbetrieb serve --help`). Written once by install.sh; an upgrade leaves it as it is.
# After a change: systemctl restart inbetrieb

# Where it listens. Beyond loopback it needs TLS (a certificate, or a reverse proxy that
# terminates TLS) and, bound to every interface, the host names clients use.
#INBETRIEB_HOST=127.0.0.1
#INBETRIEB_PORT=8000
#INBETRIEB_TLS_CERT=/etc/inbetrieb/cert.pem
#INBETRIEB_TLS_KEY=/etc/inbetrieb/key.pem
#INBETRIEB_BEHIND_PROXY=127.0.0.1
#INBETRIEB_ALLOWED_HOSTS=hmi.plant.example

# The store and the traces (traces/ beside the store by default).
#INBETRIEB_DB_PATH=/var/lib/inbetrieb/inbetrieb.sqlite
#INBETRIEB_TRACE_DIR=/var/lib/inbetrieb/traces
#INBETRIEB_RECORDINGS_QUOTA_MB=2048
#INBETRIEB_LIBRARY_QUOTA_MB=4096

# A demo lathe in a fresh store; worker processes (0: one per core); or a Ray cluster.
#INBETRIEB_DEMO=true
#INBETRIEB_WORKERS=0
#INBETRIEB_CLUSTER=ray://ray-head.plant.example:10001
EOF
    chmod 0640 "$ETC/inbetrieb.env"
fi
# an upgrade may change the kernel: numba would keep a changed callee's old code
rm -rf "$CACHE/numba"
mkdir -p "$CACHE/numba"
if [ "$CREATE_USER" = 1 ]; then
    chown "$USER_NAME:$USER_NAME" "$STATE" "$CACHE" "$CACHE/numba"
    chown "root:$USER_NAME" "$ETC/inbetrieb.env"
fi

# --- the kernel compiled now, into the service's cache (else at the first start) ---
if [ "$WARMUP" = 1 ]; then
    echo "compiling the kernel (about a minute)"
    warm="from backend.workers.warmup import warm_up; warm_up()"
    if [ "$CREATE_USER" = 1 ]; then
        (cd / && setpriv --reuid="$USER_NAME" --regid="$USER_NAME" --init-groups \
            env NUMBA_CACHE_DIR="$CACHE/numba" "$OPT/bin/python" -c "$warm")
    else
        (cd / && NUMBA_CACHE_DIR="$CACHE/numba" "$OPT/bin/python" -c "$warm")
    fi
fi

# --- the unit ---
mkdir -p "$UNIT_DIR"
install -m 0644 "$SRC/deploy/systemd/inbetrieb.service" "$UNIT_DIR/inbetrieb.service"
if [ -z "$ROOT" ] && [ -d /run/systemd/system ]; then
    systemctl daemon-reload
    echo "installed: systemctl enable --now inbetrieb (an upgrade: systemctl restart inbetrieb)"
else
    echo "installed under ${ROOT:-/} (systemd not told)"
fi
