# `cmake --install build --prefix P`: the programs in P/bin, the example rigs and body files in
# P/share/mocap, the Blender add-on's zip in P/share/mocap/blender, the udev rules in
# P/lib/udev/rules.d and the systemd user unit in P/lib/systemd/user. udev and systemd look in
# lib/ under the prefix whatever the libdir (the multiarch libdir on Debian is lib/<triplet>),
# so those two paths are fixed.
include(GNUInstallDirs)

set(_mocap_programs mocapd mocapctl mocap mocap-viewer)
foreach(p IN LISTS _mocap_programs)
  if(TARGET ${p})
    install(TARGETS ${p} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

file(GLOB _mocap_rigs CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/config/*.toml)
install(FILES ${_mocap_rigs} DESTINATION ${CMAKE_INSTALL_DATADIR}/mocap)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/body/ DESTINATION ${CMAKE_INSTALL_DATADIR}/mocap/body)
install(FILES ${CMAKE_SOURCE_DIR}/config/udev/70-mocap.rules DESTINATION lib/udev/rules.d)
install(FILES ${CMAKE_BINARY_DIR}/blender/mocap_live.zip
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocap/blender)

# The unit in config/ runs the programs from ~/.local/bin (%h/.local/bin, for a copy from a
# checkout); the installed one runs them from the install prefix, known only at install time
# (`--prefix` overrides CMAKE_INSTALL_PREFIX then), so it is written by the install script.
install(CODE "
  set(_bindir \"${CMAKE_INSTALL_BINDIR}\")
  if(NOT IS_ABSOLUTE \"\${_bindir}\")
    set(_bindir \"\${CMAKE_INSTALL_PREFIX}/\${_bindir}\")
  endif()
  file(READ \"${CMAKE_SOURCE_DIR}/config/mocapd.service\" _unit)
  string(REPLACE \"%h/.local/bin/\" \"\${_bindir}/\" _unit \"\${_unit}\")
  string(REPLACE \"cp config/mocapd.service ~/.config/systemd/user/ && cp config/witmotion.toml\"
                 \"cp \${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DATADIR}/mocap/witmotion.toml\"
                 _unit \"\${_unit}\")
  set(_dest \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/user\")
  message(STATUS \"Installing: \${_dest}/mocapd.service\")
  file(MAKE_DIRECTORY \"\${_dest}\")
  file(WRITE \"\${_dest}/mocapd.service\" \"\${_unit}\")
")
