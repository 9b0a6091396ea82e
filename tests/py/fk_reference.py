#!/usr/bin/env python3
"""Independent forward-kinematics reference for tests/robot_fk.rs, using yourdfpy.

    fk_reference.py --data-path
        prints pybullet_data.getDataPath() (where the reference robots live)
    fk_reference.py URDF CONFIGS
        CONFIGS has one configuration per line: `name=value name=value ...` (actuated joints).
        Prints, for every configuration and link, one line:
        `<config index> <link> <r00 r01 r02 t0 r10 r11 r12 t1 r20 r21 r22 t2>`
        i.e. the top three rows of the link pose in the root link frame.

Exit code 3 with a message naming the pip packages when a module is missing.
"""
import sys


def need(module):
    try:
        return __import__(module)
    except ImportError as e:
        sys.stderr.write(f"missing Python module `{module}` ({e}); run: pip install pybullet yourdfpy\n")
        sys.exit(3)


def main():
    if len(sys.argv) == 2 and sys.argv[1] == "--data-path":
        print(need("pybullet_data").getDataPath())
        return
    if len(sys.argv) != 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    yourdfpy = need("yourdfpy")
    urdf_path, cfg_path = sys.argv[1], sys.argv[2]
    # Kinematics only: no meshes, so this reference does not share our mesh resolution.
    robot = yourdfpy.URDF.load(
        urdf_path,
        build_scene_graph=True,
        load_meshes=False,
        build_collision_scene_graph=False,
        load_collision_meshes=False,
    )
    root = robot.base_link
    out = []
    with open(cfg_path) as f:
        for index, line in enumerate(f):
            cfg = {}
            for item in line.split():
                name, value = item.split("=")
                cfg[name] = float(value)
            robot.update_cfg(cfg)
            for link in robot.link_map:
                m = robot.get_transform(frame_to=link, frame_from=root)
                nums = " ".join(repr(float(m[r][c])) for r in range(3) for c in range(4))
                out.append(f"{index} {link} {nums}")
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
