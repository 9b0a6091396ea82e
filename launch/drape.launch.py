"""Start `drape node` from a ROS 2 launch (launch / launch_ros).

    ros2 launch launch/drape.launch.py
    ros2 launch launch/drape.launch.py params_file:=my_node.yaml namespace:=/robot1 \
        drape:=target/release/drape urdf:=my_robot.urdf use_sim_time:=true

drape is a plain executable, not a ROS package, so the node runs as an ExecuteProcess with the
ROS command line (`drape node --ros-args --params-file ... -r __ns:=... -p name:=value`), which
`drape node` reads the way a ROS node does. With `urdf:=FILE` the file's text is passed as the
`robot_description` parameter (URDF XML, as robot_state_publisher takes it); without it the
scene's own URDF file is used.
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
from launch.substitutions import LaunchConfiguration

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_PARAMS = os.path.normpath(os.path.join(HERE, "..", "config", "node.yaml"))


def drape_node(context):
    """The `drape node` process, its command line built from the launch arguments."""
    arg = lambda name: LaunchConfiguration(name).perform(context)  # noqa: E731
    cmd = [
        arg("drape"),
        "node",
        "--ros-args",
        "--params-file",
        arg("params_file"),
        "-r",
        "__ns:=" + arg("namespace"),
        "-p",
        "use_sim_time:=" + arg("use_sim_time"),
    ]
    urdf = arg("urdf")
    if urdf:
        with open(urdf, encoding="utf-8") as f:
            cmd += ["-p", "robot_description:=" + f.read()]
    return [ExecuteProcess(cmd=cmd, output="screen", name="drape")]


def generate_launch_description():
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "drape",
                default_value="drape",
                description="The drape executable: on PATH, or a path such as target/release/drape",
            ),
            DeclareLaunchArgument(
                "params_file",
                default_value=DEFAULT_PARAMS,
                description="ROS 2 parameters file of the node (drape: ros__parameters: ...)",
            ),
            DeclareLaunchArgument(
                "namespace", default_value="/", description="Namespace of the node"
            ),
            DeclareLaunchArgument(
                "use_sim_time",
                default_value="false",
                description="Follow /clock instead of the wall clock",
            ),
            DeclareLaunchArgument(
                "urdf",
                default_value="",
                description="URDF file passed as robot_description (empty: the scene's URDF)",
            ),
            OpaqueFunction(function=drape_node),
        ]
    )
