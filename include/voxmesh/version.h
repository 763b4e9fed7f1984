/* voxmesh's version, the one place it is written: included by voxmesh.h (C) and voxmesh.hpp
 * (C++); CMake checks that project(VERSION) says the same. Plain C. */
#ifndef VOXMESH_VERSION_H
#define VOXMESH_VERSION_H

#define VOXMESH_VERSION_MAJOR 0
#define VOXMESH_VERSION_MINOR 1
#define VOXMESH_VERSION_PATCH 0
#define VOXMESH_VERSION_STRING "0.1.0"

#endif
