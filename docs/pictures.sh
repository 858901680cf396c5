#!/usr/bin/env bash
# Regenerates every picture of the README from the examples and the benchmark, headless:
#   docs/pictures.sh
# Each command renders on whatever Vulkan driver the machine has (Mesa's lavapipe on a machine
# without a GPU; the timings printed on the pictures and in the plot name the adapter).
set -euo pipefail
cd "$(dirname "$0")/.."

example() {
    local name=$1
    shift
    cargo run --quiet --example "$name" -- --headless "$@"
}

# The showcase: ours alone (the hero), then ours | Bevy's SSAO | no AO, then four moments of the
# walkers and moving objects.
example showcase --frames 90 --layout ours --width 1280 --height 720 --out docs/showcase.png
example showcase --frames 90 --width 1500 --height 500 --out docs/showcase_thirds.png
for frames in 30 50 70 90; do
    example showcase --frames "$frames" --layout ours --width 480 --height 300 \
        --out "docs/showcase_moment_$frames.png"
done

# The smaller examples.
example basic --frames 10 --out docs/basic.png
example basic --frames 10 --debug-view --out docs/basic_debug_view.png
example deforming_characters --frames 30 --show-spheres --out docs/deforming_characters.png
example deforming_characters --frames 30 --debug-view --out docs/deforming_characters_debug_view.png
example deforming_characters --frames 30 --voxels --out docs/deforming_characters_voxels.png
example deforming_characters --frames 30 --voxels --show-voxels \
    --out docs/deforming_characters_show_voxels.png
example toasters --frames 90 --stress 24 --out docs/toasters.png
example toasters --frames 90 --stress 24 --debug-view --out docs/toasters_debug_view.png

# Cost against error (every preset and every Bevy SSAO level, timed and measured in one run), and
# ours, Bevy's SSAO High and the ground truth side by side.
cargo bench --profile dev --bench gpu_passes -- --only "preset,Bevy SSAO" \
    --plot docs/cost_error.svg --grid docs/vs_ground_truth.png
