#!/usr/bin/env bash
# `torsion run --render DIR` makes an MP4 when Debian's ffmpeg is on PATH, and only then.
# With ffmpeg: the video exists and ffprobe counts one H.264 frame per PNG picture at the asked
# size. Without ffmpeg on PATH (PATH cut down to the run): pictures only, and it says so.
# Skipped (77) when ffmpeg or ffprobe is not installed (ffmpeg is optional: scripts/setup.sh
# does not install it).
# Usage: render_mp4.sh TORSION SCENE WORKDIR
set -u
torsion=$1 scene=$2 work=$3
fail() { echo "FAIL: $*"; exit 1; }
command -v ffmpeg >/dev/null && command -v ffprobe >/dev/null ||
  { echo "ffmpeg/ffprobe not found (Debian: apt-get install ffmpeg): skipped"; exit 77; }
rm -rf "$work" && mkdir -p "$work" || fail "cannot make $work"
name=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["name"])' "$scene")

# 12 steps, a picture every 4: before the first step and after steps 4, 8, 12 -> 4 pictures.
out=$("$torsion" run "$scene" --out "$work/run" --steps 12 --threads 1 \
      --render "$work/pictures" --render-size 320x240 --render-every 4 2>&1) || { echo "$out"; fail "run failed"; }
echo "$out"
pngs=$(ls "$work/pictures"/frame_*.png 2>/dev/null | wc -l)
[ "$pngs" -eq 4 ] || fail "expected 4 pictures, found $pngs"
video="$work/pictures/$name.mp4"
[ -s "$video" ] || fail "no video $video"
probe=$(ffprobe -v error -select_streams v:0 -count_frames \
        -show_entries stream=codec_name,width,height,nb_read_frames -of default=noprint_wrappers=1 "$video")
echo "$probe"
echo "$probe" | grep -qx 'codec_name=h264' || fail "video is not H.264"
echo "$probe" | grep -qx 'width=320' || fail "video width is not 320"
echo "$probe" | grep -qx 'height=240' || fail "video height is not 240"
echo "$probe" | grep -qx "nb_read_frames=$pngs" || fail "video frame count is not $pngs"

# Without ffmpeg on PATH: the same pictures, no video, and a note saying why.
out=$(env PATH=/nonexistent "$torsion" run "$scene" --out "$work/run2" --steps 4 --threads 1 \
      --render "$work/pictures2" --render-size 320x240 --render-every 4 2>&1) || { echo "$out"; fail "run without ffmpeg failed"; }
echo "$out"
[ -e "$work/pictures2/$name.mp4" ] && fail "a video without ffmpeg on PATH"
echo "$out" | grep -q 'no ffmpeg on PATH' || fail "no note about the missing ffmpeg"
echo "PASS: $video: $pngs frames of 320x240 H.264; without ffmpeg, pictures only"
