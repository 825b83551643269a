# The daemon's I/O part: session recording (writer/reader), the pose JSON stream and VMC/OSC.
# Included by daemon/CMakeLists.txt into the mocap_daemon library.
target_sources(mocap_daemon PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/src/json_stream.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/pose_json.cpp
)
target_link_libraries(mocap_daemon PUBLIC ZLIB::ZLIB Threads::Threads)
target_sources(mocap_daemon PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/src/session.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/session_writer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/session_reader.cpp
)
target_sources(mocap_daemon PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/src/osc.cpp
  ${CMAKE_CURRENT_LIST_DIR}/src/vmc.cpp
)
