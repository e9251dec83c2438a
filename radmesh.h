// radmesh: the whole public library in one include. Scene -> mesh ->
// method (solver) -> field -> files, in the order data flows.
#pragma once

#include "radmesh_version.h"

#include "meshing/errors.h"
#include "meshing/scene.h"
#include "meshing/mesh.h"
#include "meshing/hierarchy.h"

#include "radiosity/form_factor.h"
#include "radiosity/solve.h"
#include "radiosity/hierarchical.h"
#include "radiosity/method.h"
#include "radiosity/field.h"
#include "radiosity/direct.h"
#include "radiosity/probe.h"
#include "radiosity/error_metric.h"

#include "io/obj_reader.h"
#include "io/scene_reader.h"
#include "io/vtk_writer.h"
#include "io/png_render.h"
#include "io/summary.h"
