#!/usr/bin/env bash
# gen_paths.sh - regenerates the sample camera paths in this directory
# (format: server/RECORDING.md, "oceand camera path v1").  Deterministic:
# awk evaluates the closed-form rules below; see README.md.
#   usage: clients/paths/gen_paths.sh [OUTDIR]   (default: this directory)
set -euo pipefail
out=${1:-$(dirname "$0")}
hdr='t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h'

# ship: bridge eye 25 m up, steaming along +x at 8 m/s for 60 s, reports at
# 10 Hz; the hull rolls +-2 deg (8 s period) and pitches -5 +- 1 deg (6.5 s).
awk -v hdr="$hdr" 'BEGIN {
  pi = atan2(0, -1)
  print "# oceand camera path v1"; print "# ship: 8 m/s along +x, eye 25 m, 60 s at 10 Hz (clients/paths/README.md)"; print hdr
  for (i = 0; i <= 600; i++) { t = i / 10
    printf "%.17g,%.17g,25,0,8,0,0,0,%.9g,%.9g,60,1280,720\n", t, 8 * t, -5 + sin(2 * pi * t / 6.5), 2 * sin(2 * pi * t / 8) }
}' > "$out/ship.csv"

# helicopter: hovering at 30 m (+-0.5 m bob, 5 s period), drifting on a 2 m
# circle (20 s period), turning 6 deg/s, looking 30 deg down; 30 s at 10 Hz.
awk -v hdr="$hdr" 'BEGIN {
  pi = atan2(0, -1)
  print "# oceand camera path v1"; print "# helicopter: hover at 30 m, 30 s at 10 Hz (clients/paths/README.md)"; print hdr
  for (i = 0; i <= 300; i++) { t = i / 10; w = 2 * pi / 20; b = 2 * pi / 5
    x = 2 * cos(w * t); z = 2 * sin(w * t); y = 30 + 0.5 * sin(b * t)
    vx = -2 * w * sin(w * t); vz = 2 * w * cos(w * t); vy = 0.5 * b * cos(b * t)
    yaw = 6 * t; while (yaw >= 360) yaw -= 360
    printf "%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.9g,%.9g,-30,0,70,1280,720\n", t, x, y, z, vx, vy, vz, yaw }
}' > "$out/helicopter.csv"

# jet: level pass at 150 m and 250 m/s along +x, from x = -2500 m to +2500 m
# (20 s), 300 m abeam of the origin, nose 2 deg down; reports at 30 Hz.
awk -v hdr="$hdr" 'BEGIN {
  print "# oceand camera path v1"; print "# jet: 250 m/s at 150 m, 20 s at 30 Hz (clients/paths/README.md)"; print hdr
  for (i = 0; i <= 600; i++) { t = i / 30
    printf "%.17g,%.17g,150,300,250,0,0,0,-2,0,50,1280,720\n", t, -2500 + 250 * t }
}' > "$out/jet.csv"
