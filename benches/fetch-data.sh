#!/usr/bin/env bash
# Fetch the public benchmark files the README's tables and tests use (they are not in the
# repository: their licenses do not all allow copying them), each from its repository at a
# pinned commit, and check its SHA-256 (the checksums of the files the tables were measured on).
#
#   bash benches/fetch-data.sh [FOLDER]     # default: ../shared/data beside the repository
#
# Layout of FOLDER (what tests/suite/common finds): g2o/3d/sesync, g2o/3d/gtsam, g2o/3d/mrob,
# g2o/2d/sesync, 1dsfm/Madrid_Metropolis, handeye/ethz_robot_arm_real. Needs curl, sha256sum
# and python3 (to take the hand-eye streams out of their zip). Provenance and licenses:
# SE-Sync data LGPL-3.0 repository (data from L. Carlone, Intel Research Lab / Radish), GTSAM
# BSD, mrob Apache-2.0, 1DSfM (Wilson & Snavely, ECCV 2014) via GlobalSfMpy (GPL-3.0 repository),
# the ETH robot-arm pose streams BSD-3-Clause (ethz-asl/hand_eye_calibration). Tabb's hand-eye
# dataset is not fetched: its camera file was re-typed from an index (../shared/data/README.md).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$REPO/../shared/data}"
SESYNC=https://raw.githubusercontent.com/david-m-rosen/SE-Sync/9b631b6b82d8aa7d32ab846412ae1c070412b7b6/data
GTSAM=https://raw.githubusercontent.com/borglab/gtsam/0ffe6c930302ebd297484e65e6e8d467c91d26b0/examples/Data
MROB=https://raw.githubusercontent.com/MobileRoboticsSkoltech/mrob/d7698211d90463339f109f582750b9453ac13312/benchmarks
SFM=https://raw.githubusercontent.com/zhangganlin/GlobalSfMpy/ac6a0564d84e1d6e9a4077195e384d379aa20492/datasets
ETH=https://raw.githubusercontent.com/ethz-asl/hand_eye_calibration/966cd92518f24aa7dfdacc8ba9c5fa4a441270cd/datasets/robot_arm_w_color_camera_real.zip
# path in FOLDER | URL | SHA-256
FILES="
g2o/3d/sesync/sphere2500.g2o|$SESYNC/sphere2500.g2o|104ab57593394f24351d9f692f3b923f8b98fff1eb638c64356cf5049e06cf3c
g2o/3d/sesync/parking-garage.g2o|$SESYNC/parking-garage.g2o|3ac0a31bfb601d7455d451e2546655cb5dececf51a7823f57c8a7e0fe1ca6527
g2o/3d/sesync/smallGrid3D.g2o|$SESYNC/smallGrid3D.g2o|9ea56c2ad1ebcc322560eb2f8d83cb3a60f99e2e2acc35e097b1162cdbafd649
g2o/3d/sesync/tinyGrid3D.g2o|$SESYNC/tinyGrid3D.g2o|c341eb0d09f7556b337be5a62b9354384885333a25fa718fd699fafb19620493
g2o/2d/sesync/intel.g2o|$SESYNC/intel.g2o|3e0724c048e0ba524be9dd268a8b78e19a2497043143584cbb61310638b15c4b
g2o/2d/sesync/MIT.g2o|$SESYNC/MIT.g2o|e5922be0d0689c7a5bc04c58adf3a8e697e240bdd7691cc4218470eaf92956eb
g2o/2d/sesync/CSAIL.g2o|$SESYNC/CSAIL.g2o|66d99ac857a9849d814d214a9ebd0d4876d5d40f0a37be9330c1ff6e6e9daaa6
g2o/2d/sesync/manhattan.g2o|$SESYNC/manhattan.g2o|6ae8d30971720c1af24a00c4b2dd5c5ddafbbbe488bfc771145c47decbffb248
g2o/3d/gtsam/sphere2500_groundtruth.txt|$GTSAM/sphere2500_groundtruth.txt|b9cfd29c951586bf9afc09bb8f88bf67b7436e6c988a3e208e126e7d77b4520a
g2o/3d/mrob/sphere.g2o|$MROB/sphere.g2o|be8dbad53b43695bfa3246add2f92307c3d7340fc5a5641a6f3e46e3e7d0fc61
g2o/3d/mrob/sphere_gt.g2o|$MROB/sphere_gt.g2o|3c6295c9dcbfe595c5f6e773ef2fb05a9440388ed3acdbd588aec242d8329d72
1dsfm/Madrid_Metropolis/EGs.txt|$SFM/Madrid_Metropolis/EGs.txt|98c7ec54758770068b44e08e4db234a7a99e02fab1e8e908b3ed0b57667c50c6
"
# path in FOLDER | zip URL | SHA-256 (the file of that name in the zip)
ZIPPED="
handeye/ethz_robot_arm_real/robot_arm_complete_bag_color_and_ir_base_link_sr300_hinge.csv|$ETH|3ca5f8d9858c0310a659f9c9a560509c75d2e0c0606bcef320e2f1700c9cc35c
handeye/ethz_robot_arm_real/robot_arm_complete_bag_color_and_ir_target_ir.csv|$ETH|7b5abe41d3b95b20a1abc081fc91de7181db257f9bf8777413f5ca07514cbd7d
"
# unzip_member ZIP NAME DEST: the member of ZIP whose file name is NAME, written to DEST
unzip_member() {
  python3 - "$1" "$2" "$3" <<'PYEOF'
import sys, zipfile, os
archive, name, dest = sys.argv[1:4]
with zipfile.ZipFile(archive) as z:
    members = [m for m in z.namelist() if os.path.basename(m) == name]
    if not members:
        sys.exit(f"{name} is not in {archive}")
    with open(dest, "wb") as out:
        out.write(z.read(members[0]))
PYEOF
}
# fetch_zipped DEST URL: DEST, the member of the zip at URL named as DEST is (zip kept beside)
fetch_zipped() {
  local zip
  zip="$OUT/.$(basename "$2")"
  [[ -s "$zip" ]] || curl -fsSL --retry 3 -o "$zip" "$2" || { echo "download failed: $2" >&2; return 1; }
  unzip_member "$zip" "$(basename "$1")" "$1"
}
# fetch_plain DEST URL: DEST downloaded from URL
fetch_plain() {
  curl -fsSL --retry 3 -o "$1.part" "$2" && mv "$1.part" "$1" || { echo "download failed: $2" >&2; return 1; }
}
failed=0
# fetch LINES HOW: each `path|url|sum` line fetched by HOW unless present with its checksum,
# then checked
fetch() {
  local line path url sum dest
  for line in $1; do
    IFS='|' read -r path url sum <<<"$line"
    dest="$OUT/$path"
    mkdir -p "$(dirname "$dest")"
    if [[ ! -f "$dest" ]] || ! echo "$sum  $dest" | sha256sum --check --status; then
      "$2" "$dest" "$url" || { failed=1; continue; }
    fi
    if echo "$sum  $dest" | sha256sum --check --status; then
      echo "ok $path"
    else
      echo "CHECKSUM MISMATCH $path (expected $sum)" >&2
      failed=1
    fi
  done
}
fetch "$ZIPPED" fetch_zipped
fetch "$FILES" fetch_plain
exit $failed
