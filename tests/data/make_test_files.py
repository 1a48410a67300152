"""Regenerates the hand-made mocap test files in this folder: python make_test_files.py"""

from pathlib import Path

import numpy as np

D = Path(__file__).parent

# ---- BVH: 40 frames at 40 fps, body yawed 30 deg, arms raised sideways, elbows bending
T = 40
s = np.linspace(0, 1, T)
gamma = -60 + 120 * s  # arm elevation from horizontal, deg -> abduction 90 + gamma
delta = 20 + 60 * s  # elbow bend, deg
hier = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftShoulder
    {
      OFFSET 3 40 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT LeftArm
      {
        OFFSET 15 0 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT LeftForeArm
        {
          OFFSET 28 0 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT LeftHand
          {
            OFFSET 25 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            End Site
            {
              OFFSET 15 0 0
            }
          }
        }
      }
    }
    JOINT RightShoulder
    {
      OFFSET -3 40 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightArm
      {
        OFFSET -15 0 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT RightForeArm
        {
          OFFSET -28 0 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT RightHand
          {
            OFFSET -25 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            End Site
            {
              OFFSET -15 0 0
            }
          }
        }
      }
    }
    JOINT Neck
    {
      OFFSET 0 45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 20 0
      }
    }
  }
}
MOTION
Frames: N_FRAMES
Frame Time: 0.025
""".replace("N_FRAMES", str(T))
rows = []
for t in range(T):
    v = [2.0 * s[t], 90.0, -1.0 * s[t], 0, 0, 30.0]  # hips: moving, yawed 30 deg
    v += [0, 0, 0]  # spine
    v += [0, 0, 0, gamma[t], 0, 0, delta[t], 0, 0, 0, 0, 0]  # left clavicle, arm, forearm, hand
    v += [0, 0, 0, -gamma[t], 0, 0, -delta[t], 0, 0, 0, 0, 0]  # right
    v += [0, 0, 0]  # neck
    rows.append(" ".join(f"{x:.6f}" for x in v))
(D / "arms.bvh").write_text(hier + "\n".join(rows) + "\n")
bad = hier.replace(
    "CHANNELS 3 Zrotation Xrotation Yrotation\n        JOINT LeftForeArm",
    "CHANNELS 3 Zrotation Xrotation\n        JOINT LeftForeArm",
    1,
)
assert bad != hier
(D / "bad_channels.bvh").write_text(bad + "\n".join(rows) + "\n")

# ---- ASF/AMC: a tiny y-up skeleton facing +z, CRLF line ends
asf = """# tiny hand-made skeleton for tests (y up, facing +z)
:version 1.10
:name tiny
:units
  mass 1.0
  length 0.45
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name lowerback
     direction 0 1 0
     length 8
     axis 0 0 0  XYZ
    dof rx ry rz
  end
  begin
     id 2
     name lclavicle
     direction 1 0 0
     length 3
     axis 0 0 0  XYZ
  end
  begin
     id 3
     name lhumerus
     direction 1 0 0
     length 5
     axis 0 0 0  XYZ
    dof rx ry rz
  end
  begin
     id 4
     name lradius
     direction 1 0 0
     length 4
     axis 0 0 0  XYZ
    dof rz
  end
  begin
     id 5
     name rclavicle
     direction -1 0 0
     length 3
     axis 0 0 0  XYZ
  end
  begin
     id 6
     name rhumerus
     direction -1 0 0
     length 5
     axis 0 0 0  XYZ
    dof rx ry rz
  end
  begin
     id 7
     name rradius
     direction -1 0 0
     length 4
     axis 0 0 0  XYZ
    dof rz
  end
:hierarchy
  begin
    root lowerback
    lowerback lclavicle rclavicle
    lclavicle lhumerus
    lhumerus lradius
    rclavicle rhumerus
    rhumerus rradius
  end
"""


def crlf(t):
    return t.replace("\n", "\r\n")


(D / "tiny.asf").write_bytes(crlf(asf).encode())
noarms = asf.replace("lhumerus", "lfemur").replace("rhumerus", "rfemur")
(D / "noarms.asf").write_bytes(crlf(noarms).encode())
n = 24
frames = [":FULLY-SPECIFIED", ":DEGREES"]
for t in range(n):
    g = -40 + 80 * t / (n - 1)
    d = 20 + 50 * t / (n - 1)
    frames += [
        str(t + 1),
        "root 0 17 0 0 25 0",
        "lowerback 0 0 0",
        f"lhumerus 0 0 {g:.4f}",
        f"lradius {d:.4f}",
        f"rhumerus 0 0 {-g:.4f}",
        f"rradius {-d:.4f}",
    ]
good = "\n".join(frames) + "\n"
(D / "tiny.amc").write_bytes(crlf(good).encode())
lines = good.splitlines()
trunc = "\n".join(lines[:-3]) + "\n"  # last frame loses its last 3 bones
(D / "bad_truncated.amc").write_bytes(crlf(trunc).encode())
cnt = good.replace("lradius 20.0000", "lradius 20.0000 1.0", 1)
assert cnt != good
(D / "bad_count.amc").write_text(cnt)
tok = good.replace("rhumerus 0 0 40.0000", "rhumerus 0 zero 40.0000", 1)
assert tok != good
(D / "bad_token.amc").write_text(tok)
