#!/usr/bin/env bash
# Installs the Debian 12 packages fitroom needs, if any are missing. Sourced by the other scripts.
#   runtime: Vulkan loader + Mesa (lavapipe renders on any machine without a GPU), X11 client libs
#   tests:   Xvfb for the windowed kiosk screenshot
#   Kinect:  libfreenect (loaded at run time by `--sensor kinect`; its fakenect replay library,
#            /usr/lib/x86_64-linux-gnu/fakenect, runs the live source's test) and its tools
fitroom_install_deps() {
    local packages=(mesa-vulkan-drivers libvulkan1 libx11-6 libxcursor1 libxrandr2 libxi6
                    libxkbcommon-x11-0 xvfb xauth libfreenect-dev libfreenect-bin)
    local missing=()
    for p in "${packages[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if ((${#missing[@]})); then
        local sudo=""
        [ "$(id -u)" -ne 0 ] && sudo="sudo"
        echo "installing: ${missing[*]}"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    fi
}
