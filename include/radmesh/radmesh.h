// radmesh: the whole public library in one include, in the order data
// flows: scene -> mesh -> method (solver) -> field -> files. The common case
// is one call, radmesh::solve (run.h).
#pragma once

#include "radmesh/version.h"

#include "radmesh/errors.h"
#include "radmesh/options.h"
#include "radmesh/progress.h"
#include "radmesh/geometry.h"

#include "radmesh/scene.h"
#include "radmesh/scene_reader.h"
#include "radmesh/obj_reader.h"

#include "radmesh/mesh.h"
#include "radmesh/discontinuity.h"
#include "radmesh/hierarchy.h"

#include "radmesh/form_factor.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"
#include "radmesh/hierarchical.h"
#include "radmesh/pixmap.h"
#include "radmesh/method.h"
#include "radmesh/run.h"

#include "radmesh/field.h"
#include "radmesh/direct.h"
#include "radmesh/probe.h"
#include "radmesh/probe_file.h"
#include "radmesh/error_metric.h"

#include "radmesh/output_batch.h"
#include "radmesh/vtk_writer.h"
#include "radmesh/summary.h"
#include "radmesh/png_render.h"
#include "radmesh/histogram.h"
