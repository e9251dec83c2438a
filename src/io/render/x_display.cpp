// The X display connection VTK's render windows borrow (x_display.h): the
// one place Xlib is included.

#include "io/render/x_display.h"

#include <X11/Xlib.h>

namespace radmesh::internal {

XConnection::XConnection() : display_(XOpenDisplay(nullptr)) {}

XConnection::~XConnection() {
  if (display_ != nullptr) XCloseDisplay(static_cast<Display*>(display_));
}

}  // namespace radmesh::internal
