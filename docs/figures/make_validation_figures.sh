#!/usr/bin/env bash
# Regenerates the data and the PNG figures of docs/validation.md:
#   bash docs/figures/make_validation_figures.sh [BUILD_DIR]
# Runs the physics tests with TORSION_VALIDATION_OUT set (they then write their data as CSV) and
# plots it with gnuplot (Debian's gnuplot-nox, installed here when missing and running as root).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
out=docs/figures
command -v gnuplot >/dev/null || { [ "$(id -u)" -eq 0 ] && apt-get install -y -qq gnuplot-nox; }

TORSION_VALIDATION_OUT=$out "$build/tests/torsion_physics_tests" --gtest_filter='Cantilever.*:StVenant*:HandFastMotion.*'

gnuplot <<GP
set datafile separator ","
set terminal pngcairo size 800,500 font "sans,11"
set grid

set output "$out/st_venant_two_pi_profile.png"
set title "2 pi twist of the 8332-tet cylinder (0.1 rad/s, dt = 0.01): section angle along z"
set xlabel "z (m)"; set ylabel "theta(z) (rad)"; set key top left
plot "$out/st_venant_two_pi_profile.csv" skip 1 using 1:2 with points pt 7 ps 0.8 title "FEM (least-squares slice rotation)", \
     "" skip 1 using 1:3 with lines lw 2 title "St-Venant theta_L z / L"

set output "$out/st_venant_convergence.png"
set title "Small twist (0.05 rad): torque / (G J theta') vs mesh size"
set xlabel "tets"; set ylabel "T / (G J theta')"; set logscale x; set key top right; set yrange [0.95:1.4]
plot "$out/st_venant_small_twist.csv" skip 1 using 1:4 with linespoints pt 7 lw 2 title "FEM, corotated linear tets", \
     1 with lines dt 2 title "St-Venant"
unset logscale x; set autoscale y

set output "$out/cantilever_convergence.png"
set title "Cantilever under gravity (10 x 1 x 1 m, E = 1e9 Pa): tip deflection"
set xlabel "tets"; set ylabel "tip deflection (m)"; set logscale x; set key bottom right
plot "$out/cantilever.csv" skip 1 using 2:3 with linespoints pt 7 lw 2 title "FEM", \
     "" skip 1 using 2:4 with lines dt 2 title "Timoshenko", "" skip 1 using 2:5 with lines dt 3 title "Euler-Bernoulli"

set output "$out/hand_fast_turn_strain.png"
set title "Hand turned 90 degrees in 30 ms on the 2430-tet cylinder (E = 1e5 Pa): worst element strain"
set xlabel "time (s)"; set ylabel "max |s_i - 1| over tets"; set logscale y; set key top right
set xrange [0:3.03]
plot "$out/hand_fast_turn.csv" skip 1 using 1:2 with lines lw 2 title "no speed limit (patch lands on the device frame)", \
     "" skip 1 using 1:4 with lines lw 2 title "speed limit 0.2 c_s = 1.24 m/s (default)"
unset logscale y

set output "$out/hand_fast_turn_inverted.png"
set title "Same run: inverted tets (det F <= 0)"
set xlabel "time (s)"; set ylabel "inverted tets"; set key top right; set xrange [0:1]
plot "$out/hand_fast_turn.csv" skip 1 using 1:3 with steps lw 2 title "no speed limit", \
     "" skip 1 using 1:5 with steps lw 2 title "speed limit (default)"
set autoscale x
GP
echo "figures in $out/"
