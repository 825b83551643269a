# Tests of the session files the daemon records and `mocap export` reads: real files, processes.
find_package(nlohmann_json 3.11 REQUIRED)
mocap_test(test_session SOURCES test_session.cpp LIBS mocap_daemon TIMEOUT 120)
mocap_test(test_session_compression SOURCES test_session_compression.cpp LIBS mocap_daemon
  TIMEOUT 120)
mocap_test(test_session_crash SOURCES test_session_crash.cpp LIBS mocap_daemon TIMEOUT 120)
mocap_test(test_session_export SOURCES test_session_export.cpp
  LIBS mocap_daemon mocap_skeleton nlohmann_json::nlohmann_json ZLIB::ZLIB TIMEOUT 60)
add_dependencies(test_session_export mocap)
