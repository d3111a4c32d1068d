#!/usr/bin/env bash
# The synthetic depth recordings the skeleton tracker (issue 24) is evaluated on:
# every shared CMU clip (data/mocap/cmu/INDEX.tsv, 15 clips) x three ANSUR II bodies x
# {no garment, T-shirt, sun dress}: 135 recordings.
#
#   scripts/track_matrix.sh OUT_DIR [FRAMES]
#
# Each recording is `fitroom sensor record --synthetic --treadmill --distance-m $DISTANCE` (default 3) (the clip
# replayed on the spot, so that a walk stays in the camera's view and range), FRAMES depth frames
# (default 150, 5 s), written to OUT_DIR/<clip>_<body>_<garment>/ (the fakenect dump,
# groundtruth.jsonl, body.json; record.json is the command's report). The noise seed differs per
# recording and depends only on its place in the matrix (the clip's row in INDEX.tsv, the body,
# the garment), so a resumed or partial run records the same thing.
#
# Resumable: a recording that exists is skipped. A recording is written to <name>.partial and
# moved in place only when it is complete, so an interrupted run leaves nothing that looks done.
# A recording that fails is reported (its log kept in OUT_DIR/logs/) and the others go on; the
# script then exits with status 1.
#
# The bodies (OUT_DIR/bodies/<body>.ron, with the fit's report <body>.fit.json) are fitted with
# `fitroom body fit` to the nine ANSUR II measurements of one real subject each (the columns
# `fitroom body ansur` fits; ANSUR II public tables in data/ansur2, cm). Chosen among the subjects
# nearest to the target stature and weight (in standard deviations of the table) the one whose
# other girths and lengths are most typical of those neighbours:
#   small_woman  female subject 13371, age 26: stature 152.6 cm (female table's 5th percentile:
#                152.5), weight 52.2 kg (5th percentile 51.3 kg); crotch height 71.4,
#                biacromial 35.2, neck 34.8, chest 81.0, waist (navel) 72.1, buttock 87.6,
#                thigh 53.1, calf 34.8.
#   median_man   male subject 29227, age 28: stature 175.5 cm (male 50th percentile: 175.5),
#                weight 84.4 kg (50th percentile 84.6 kg), BMI 27.4; crotch 82.5, biacromial
#                41.8, neck 42.6, chest 104.7, waist 96.1, buttock 101.0, thigh 61.4, calf 37.9.
#   heavy_man    male subject 12911, age 28: weight 110.8 kg (male 95th percentile: 110.7 kg),
#                BMI 34.9 (95th percentile 34.8), stature 178.2 cm; crotch 82.6, biacromial
#                45.5, neck 44.2, chest 120.8, waist 110.7, buttock 115.3, thigh 73.0,
#                calf 44.6.
#
# Garment sizes (the garments' own size charts): T-shirt S (body chest 90) for the small woman,
# L (chest 102; the garment has 10 cm of ease) for the median man, XL (chest 108, the largest) for
# the heavy man; sun dress 36 for the small woman (`fitroom body size` with the EN 13402 chart
# gives 36 for her waist), 42 (the largest) for both men.
#
# Environment:
#   FITROOM  the binary (default: ${CARGO_TARGET_DIR:-$HOME/.cache/fitroom-target}/release/fitroom;
#            build it with `cargo build --release --bin fitroom`)
#   CLIPS    only these clips, e.g. CLIPS="07_01 141_16" (default: all of INDEX.tsv)
#   GARMENTS only these garment choices, e.g. GARMENTS="none tshirt" (default: none tshirt
#            sundress); a recording's seed is the whole matrix's either way
#   SEED_OFFSET added to every recording's noise seed (default 0): the same motions and bodies
#            under other noise, to check a change on recordings it was not tuned on
set -euo pipefail

die() {
    echo "track_matrix: error: $*" >&2
    exit 1
}

if [[ $# -lt 1 || $# -gt 2 || $1 == -h || $1 == --help ]]; then
    echo "usage: $0 OUT_DIR [FRAMES]   (FRAMES: depth frames per recording, default 150)" >&2
    exit 2
fi
FRAMES=${2:-150}
SEED_OFFSET=${SEED_OFFSET:-0}
[[ $SEED_OFFSET =~ ^[0-9]+$ ]] || die "SEED_OFFSET must be a whole number, not: $SEED_OFFSET"
# The person's distance from the sensor, metres (3 m: a 1.8 m person with raised arms stays
# below the image's top edge with the sensor 0.8 m up; 2.5 m cuts heads and hands).
DISTANCE=${DISTANCE:-3.0}
[[ $FRAMES =~ ^[1-9][0-9]*$ ]] || die "FRAMES must be a positive whole number, not '$FRAMES'"
mkdir -p -- "$1" || die "cannot create the output folder '$1'"
OUT=$(cd -- "$1" && pwd)
ROOT=$(cd -- "$(dirname -- "${BASH_SOURCE[0]}")/.." && pwd)

FITROOM=${FITROOM:-${CARGO_TARGET_DIR:-$HOME/.cache/fitroom-target}/release/fitroom}
if [[ ! -x $FITROOM ]]; then
    die "no fitroom binary at '$FITROOM'; build it first:
    cd $ROOT && CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$HOME/.cache/fitroom-target} cargo build --release --bin fitroom
(or set FITROOM to the binary)"
fi
if ! "$FITROOM" sensor record --help 2>/dev/null | grep -q -- '--treadmill'; then
    die "'$FITROOM' has no \`sensor record --treadmill\`: it is older than the treadmill option (or \
was rebuilt from another checkout); rebuild it from this one: cd $ROOT && cargo build --release --bin fitroom"
fi
# The binary finds assets/ in the working folder; the clips and garments are named from here.
cd -- "$ROOT"

INDEX=data/mocap/cmu/INDEX.tsv
[[ -f $INDEX ]] || die "no clip index '$ROOT/$INDEX'"
mapfile -t ALL_CLIPS < <(tail -n +2 "$INDEX" | cut -f1 | sed -e 's/\.bvh$//' -e '/^$/d')
[[ ${#ALL_CLIPS[@]} -gt 0 ]] || die "'$INDEX' lists no clip"
if [[ -n ${CLIPS:-} ]]; then
    read -r -a SELECTED <<<"$CLIPS"
else
    SELECTED=("${ALL_CLIPS[@]}")
fi
# The place of NAME in the list that follows it (for the seed: a clip's row in INDEX.tsv, a
# garment choice's in the whole matrix); fails if it is not there.
index_of() {
    local name=$1 i=0 item
    shift
    for item in "$@"; do
        if [[ $item == "$name" ]]; then
            echo "$i"
            return 0
        fi
        i=$((i + 1))
    done
    return 1
}
clip_row() { index_of "$1" "${ALL_CLIPS[@]}"; }
for clip in "${SELECTED[@]}"; do
    clip_row "$clip" >/dev/null || die "clip '$clip' is not in $INDEX (clips: ${ALL_CLIPS[*]})"
    [[ -f data/mocap/cmu/$clip.bvh.gz ]] || die "missing clip file data/mocap/cmu/$clip.bvh.gz"
done

BODIES=(small_woman median_man heavy_man)
declare -A FIT=(
    [small_woman]="--gender female --age 26 --stature 152.6 --inside-leg 71.4 --shoulder-width 35.2 --neck 34.8 --bust 81.0 --navel-waist 72.1 --hip 87.6 --thigh 53.1 --calf 34.8"
    [median_man]="--gender male --age 28 --stature 175.5 --inside-leg 82.5 --shoulder-width 41.8 --neck 42.6 --bust 104.7 --navel-waist 96.1 --hip 101.0 --thigh 61.4 --calf 37.9"
    [heavy_man]="--gender male --age 28 --stature 178.2 --inside-leg 82.6 --shoulder-width 45.5 --neck 44.2 --bust 120.8 --navel-waist 110.7 --hip 115.3 --thigh 73.0 --calf 44.6"
)
ALL_GARMENTS=(none tshirt sundress)
if [[ -n ${GARMENTS:-} ]]; then
    read -r -a GARMENTS <<<"$GARMENTS"
else
    GARMENTS=("${ALL_GARMENTS[@]}")
fi
garment_row() { index_of "$1" "${ALL_GARMENTS[@]}"; }
for garment in "${GARMENTS[@]}"; do
    garment_row "$garment" >/dev/null ||
        die "garment choice '$garment' is not one of: ${ALL_GARMENTS[*]}"
done
declare -A GARMENT_FILE=([tshirt]=assets/garments/tshirt.ron [sundress]=assets/garments/sundress.ron)
declare -A SIZE=(
    [small_woman.tshirt]=S [median_man.tshirt]=L [heavy_man.tshirt]=XL
    [small_woman.sundress]=36 [median_man.sundress]=42 [heavy_man.sundress]=42
)
for g in "${!GARMENT_FILE[@]}"; do
    [[ -f ${GARMENT_FILE[$g]} ]] || die "missing garment ${GARMENT_FILE[$g]}"
done

mkdir -p "$OUT/bodies" "$OUT/logs"
for body in "${BODIES[@]}"; do
    shape=$OUT/bodies/$body.ron
    if [[ -f $shape ]]; then
        echo "body $body: $shape exists"
        continue
    fi
    # shellcheck disable=SC2086 # FIT holds the options, split on purpose
    if ! "$FITROOM" body fit ${FIT[$body]} --json --out "$shape.partial" \
        >"$OUT/bodies/$body.fit.json" 2>"$OUT/logs/body_$body.log"; then
        rm -f -- "$shape.partial"
        cat "$OUT/logs/body_$body.log" >&2
        die "fitting the body $body failed (log: $OUT/logs/body_$body.log)"
    fi
    mv -- "$shape.partial" "$shape"
    rm -f -- "$OUT/logs/body_$body.log"
    echo "body $body: fitted to ${FIT[$body]} -> $shape"
done

now() { date +%s.%N; }
# Seconds as "1 h 02 min", "3 min 05 s" or "12 s".
human() {
    awk -v s="$1" 'BEGIN {
        s = int(s + 0.5)
        if (s >= 3600) printf "%d h %02d min", s / 3600, (s % 3600) / 60
        else if (s >= 60) printf "%d min %02d s", s / 60, s % 60
        else printf "%d s", s
    }'
}

# Depth frames (30 Hz) within a clip's length (INDEX.tsv: frames, frame time), at most FRAMES.
clip_frames() {
    awk -F'\t' -v clip="$1.bvh" -v most="$FRAMES" \
        '$1 == clip { n = int($4 * $5 * 30) - 1; print (n < most ? n : most); exit }' "$INDEX"
}
total=$((${#SELECTED[@]} * ${#BODIES[@]} * ${#GARMENTS[@]}))
done_count=0 skipped=0 made=0 spent=0
failed=()
# A recording is there when the folder holds its dump, ground truth and body.json (written last).
exists() { [[ -f $1/body.json && -f $1/groundtruth.jsonl && -f $1/INDEX.txt ]]; }
# Per garment choice: recordings missing at the start, tried so far (made or failed), made, and
# seconds spent making them.
declare -A todo_g=() tried_g=() made_g=() spent_g=()
todo=0
for garment in "${GARMENTS[@]}"; do
    todo_g[$garment]=0 tried_g[$garment]=0 made_g[$garment]=0 spent_g[$garment]=0
done
for clip in "${SELECTED[@]}"; do
    for body in "${BODIES[@]}"; do
        for garment in "${GARMENTS[@]}"; do
            if ! exists "$OUT/${clip}_${body}_${garment}"; then
                todo_g[$garment]=$((${todo_g[$garment]} + 1))
                todo=$((todo + 1))
            fi
        done
    done
done
# The whole matrix (every clip of the index, whatever CLIPS selects), per garment choice.
per_garment=$((${#ALL_CLIPS[@]} * ${#BODIES[@]}))
echo "$total recordings (${#SELECTED[@]} clips x ${#BODIES[@]} bodies x ${#GARMENTS[@]} garment choices), at most $FRAMES frames each (the clip's length), into $OUT: $todo to record, $((total - todo)) already there"
# Seconds the recordings still to come would take (with `all`: the whole matrix of every clip,
# recorded from scratch): each garment
# choice at its mean so far (the overall mean for one not timed yet).
eta() {
    local garment est=0 mean left
    for garment in "${GARMENTS[@]}"; do
        if [[ ${made_g[$garment]} -gt 0 ]]; then
            mean=$(awk -v a="${spent_g[$garment]}" -v n="${made_g[$garment]}" 'BEGIN { print a / n }')
        else
            mean=$(awk -v a="$spent" -v n="$made" 'BEGIN { print a / n }')
        fi
        left=$((${todo_g[$garment]} - ${tried_g[$garment]}))
        [[ ${1:-} == all ]] && left=$per_garment
        est=$(awk -v e="$est" -v m="$mean" -v l="$left" 'BEGIN { print e + m * l }')
    done
    echo "$est"
}
for clip in "${SELECTED[@]}"; do
    row=$(clip_row "$clip")
    for bi in "${!BODIES[@]}"; do
        body=${BODIES[$bi]}
        for garment in "${GARMENTS[@]}"; do
            gi=$(garment_row "$garment")
            done_count=$((done_count + 1))
            name=${clip}_${body}_${garment}
            dir=$OUT/$name
            tag="[$done_count/$total] $name"
            if exists "$dir"; then
                echo "$tag: exists, skipped"
                skipped=$((skipped + 1))
                continue
            fi
            if [[ -e $dir ]]; then
                echo "$tag: incomplete folder, recording it again"
                rm -rf -- "$dir"
            fi
            seed=$((1 + (row * ${#BODIES[@]} + bi) * ${#ALL_GARMENTS[@]} + gi + SEED_OFFSET))
            # No more frames than the clip lasts: past its end the clip starts again, and the
            # jump back to its first pose is no motion a person makes.
            frames=$(clip_frames "$clip")
            args=(sensor record --synthetic --motion "data/mocap/cmu/$clip.bvh.gz" --treadmill
                --shape "$OUT/bodies/$body.ron" --distance-m "$DISTANCE" --frames "$frames"
                --seed "$seed")
            if [[ $garment != none ]]; then
                args+=(--garment "${GARMENT_FILE[$garment]}" --size "${SIZE[$body.$garment]}")
            fi
            part=$dir.partial
            log=$OUT/logs/$name.log
            tried_g[$garment]=$((${tried_g[$garment]} + 1))
            rm -rf -- "$part"
            start=$(now)
            if "$FITROOM" "${args[@]}" --out "$part" >"$OUT/logs/$name.json" 2>"$log"; then
                # The report names the folder it was written to: the final one.
                esc=${dir//\\/\\\\}
                esc=${esc//&/\\&}
                esc=${esc//|/\\|}
                sed -e "s|\"out\": \".*\.partial\"|\"out\": \"$esc\"|" "$OUT/logs/$name.json" \
                    >"$part/record.json"
                rm -f -- "$OUT/logs/$name.json"
                mv -- "$part" "$dir"
                rm -f -- "$log"
            else
                echo "$tag: FAILED (seed $seed); last lines of $log:" >&2
                tail -n 5 "$log" >&2
                failed+=("$name")
                rm -rf -- "$part" "$OUT/logs/$name.json"
                continue
            fi
            took=$(awk -v a="$start" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }')
            made=$((made + 1))
            spent=$(awk -v a="$spent" -v b="$took" 'BEGIN { print a + b }')
            made_g[$garment]=$((${made_g[$garment]} + 1))
            spent_g[$garment]=$(awk -v a="${spent_g[$garment]}" -v b="$took" 'BEGIN { print a + b }')
            echo "$tag: ${took} s (seed $seed), $((todo - made - ${#failed[@]})) to go, about $(human "$(eta)") left"
            if [[ ${made_g[$garment]} -eq 1 ]]; then
                # The first timed recording of this garment choice: the estimate for all of them.
                echo "  one recording ($garment, $frames frames) took ${took} s: $per_garment such recordings take about $(human "$(awk -v t="$took" -v n="$per_garment" 'BEGIN { print t * n }')"); the whole matrix of $((per_garment * ${#GARMENTS[@]})) (all clips), at the times measured so far, about $(human "$(eta all)")"
            fi
        done
    done
done

echo "done: $made recorded, $skipped skipped (already there), ${#failed[@]} failed; $(human "$spent") recording, into $OUT"
if [[ ${#failed[@]} -gt 0 ]]; then
    echo "failed (logs in $OUT/logs/): ${failed[*]}" >&2
    exit 1
fi
