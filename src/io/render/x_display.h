// Private to io/ and bench/: an X display connection for VTK's render windows.
// VTK aborts the process when a render window cannot open a display, so a
// caller opens one with XConnection first, before any VTK rendering object
// exists, and hands this same connection to the window (SetDisplayId): the
// display that was checked is the one used. No X header here: Xlib's macros
// (None, Bool, Status, ...) clash with C++ headers.
#pragma once

namespace radmesh::internal {

// What a function that needs a display reports (through its `why`) without one.
inline constexpr const char* kNoDisplayReason =
    "no X display (DISPLAY unset or unreachable); run under xvfb-run to get the PNG";

// XOpenDisplay(nullptr), closed at scope exit. Declare it before the render
// window that borrows it, so that it outlives the window.
class XConnection {
public:
  XConnection();
  ~XConnection();
  XConnection(const XConnection&) = delete;
  XConnection& operator=(const XConnection&) = delete;

  // The Display*, typed as vtkRenderWindow::SetDisplayId takes it; null when
  // no display could be opened.
  void* get() const { return display_; }

private:
  void* display_;
};

}  // namespace radmesh::internal
