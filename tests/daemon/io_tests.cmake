# Tests of the daemon's I/O part (recording, JSON stream, VMC): real files, sockets, processes.
find_package(nlohmann_json 3.11 REQUIRED)
mocap_test(test_json_stream SOURCES test_json_stream.cpp
  LIBS mocap_daemon nlohmann_json::nlohmann_json TIMEOUT 120)
