// radmesh: the whole public library in one include. Scene -> mesh ->
// method (solver) -> field -> files, in the order data flows.
#pragma once

#include "radmesh/version.h"

#include "radmesh/errors.h"
#include "radmesh/scene.h"
#include "radmesh/mesh.h"
#include "radmesh/hierarchy.h"

#include "radmesh/form_factor.h"
#include "radmesh/solve.h"
#include "radmesh/hierarchical.h"
#include "radmesh/method.h"
#include "radmesh/field.h"
#include "radmesh/direct.h"
#include "radmesh/probe.h"
#include "radmesh/error_metric.h"

#include "radmesh/obj_reader.h"
#include "radmesh/scene_reader.h"
#include "radmesh/vtk_writer.h"
#include "radmesh/png_render.h"
#include "radmesh/summary.h"
