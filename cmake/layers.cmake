# The layer order, bottom up (ARCHITECTURE.md). For every layer library a
# small executable links the library's whole archive (every object, used or
# not) with only the libraries the layer declares: a call from a layer into
# one above it leaves an undefined symbol and the build fails. Header-only
# upward includes are caught by scripts/check-layers (ctest: layers_includes).
set(GRADUS_LAYER_LIBRARIES
  gradus_core gradus_image gradus_parser gradus_samplers gradus_media gradus_textures
  gradus_materials gradus_reconstruction gradus_manifold gradus_scene gradus_render
  gradus_integrators gradus_job)
foreach(lib ${GRADUS_LAYER_LIBRARIES})
  add_executable(layercheck_${lib} ${CMAKE_SOURCE_DIR}/cmake/layercheck_main.cpp)
  target_link_libraries(layercheck_${lib} PRIVATE "$<LINK_LIBRARY:WHOLE_ARCHIVE,${lib}>")
  set_target_properties(layercheck_${lib} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/layercheck)
endforeach()
