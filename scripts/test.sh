#!/usr/bin/env bash
# Runs the whole test suite, GPU trials included, on lavapipe (Mesa's software Vulkan) when
# the machine has no other Vulkan driver. Installs the Debian packages it needs when missing.
# Extra arguments go to `cargo test --workspace`, e.g. `scripts/test.sh -- --nocapture`.
set -euo pipefail
cd "$(dirname "$0")/.."

# fonts-dejavu-core: the bench draws its chart with DejaVu Sans.
packages=(mesa-vulkan-drivers libvulkan1 spirv-tools glslang-tools fonts-dejavu-core)
missing=()
if command -v dpkg-query >/dev/null 2>&1; then
    for pkg in "${packages[@]}"; do
        if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
            missing+=("$pkg")
        fi
    done
else
    echo "scripts/test.sh: not a Debian system; make sure Vulkan (or lavapipe), spirv-val and glslangValidator are installed" >&2
fi
if [ ${#missing[@]} -gt 0 ]; then
    sudo=()
    if [ "$(id -u)" -ne 0 ]; then sudo=(sudo); fi
    echo "scripts/test.sh: installing ${missing[*]}" >&2
    "${sudo[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Mesa's WSI complains without a runtime dir.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    XDG_RUNTIME_DIR="$(mktemp -d)"
    chmod 700 "$XDG_RUNTIME_DIR"
    export XDG_RUNTIME_DIR
fi

# Without a Vulkan driver wgpu would fall back to GL silently; GL is not built in, but be explicit.
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"

# Point the Vulkan loader at lavapipe only when no other driver can work: no other ICD is
# installed, or the others (mesa-vulkan-drivers also ships intel/radeon ICDs) have no GPU
# device node to drive. With a real GPU nothing is overridden and the runtime prefers it.
if [ -z "${VK_ICD_FILENAMES:-}" ] && [ -z "${VK_DRIVER_FILES:-}" ]; then
    lvp=""
    others=0
    for dir in /usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d; do
        [ -d "$dir" ] || continue
        for icd in "$dir"/*.json; do
            [ -e "$icd" ] || continue
            case "$(basename "$icd")" in
                lvp_icd*.json)
                    if [ -z "$lvp" ] || [[ "$icd" == *"$(uname -m)"* ]]; then lvp="$icd"; fi
                    ;;
                *) others=$((others + 1)) ;;
            esac
        done
    done
    hardware=0
    if compgen -G "/dev/dri/renderD*" >/dev/null || compgen -G "/dev/nvidia[0-9]*" >/dev/null; then
        hardware=1
    fi
    if [ -n "$lvp" ] && { [ "$others" -eq 0 ] || [ "$hardware" -eq 0 ]; }; then
        export VK_ICD_FILENAMES="$lvp" VK_DRIVER_FILES="$lvp"
        echo "scripts/test.sh: no hardware Vulkan driver; using lavapipe ($lvp)" >&2
    fi
fi

exec cargo test --workspace "$@"
