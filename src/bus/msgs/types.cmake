# The rilbed LCM message types (src/bus/msgs/<type>.lcm), for lcm-gen: one list for the
# main build, the Java jar and the fuzz project. Add a type here when you add a .lcm file.
set(RILBED_LCM_TYPES robot_pose_t poses_t event_t status_t polyline_t world_t summary_t console_command_t
    console_reply_t robot_wheels_t wheels_t robot_sensors_t sensors_t detection_t detections_t frame_t
    camera_t sensor_geometry_t sensor_layout_t vision_settings_t agent_hello_t agent_input_t team_member_t quantum_t
    agent_output_t quantum_reply_t robot_body_t robot_bodies_t
    model_reading_t sensor_mark_t robot_models_t sensor_models_t)
