// TetGen stops on an error through terminatetetgen(mesh, code) (tetgen.h), which in Debian's TetGen 1.5.0 frees the
// mesh's memory pools and throws; unwinding then runs ~tetgenmesh, which frees them again: a double free that
// crashes the process (seen on a self-intersecting surface; TetGen 1.6 clears the pointers). The library calls the
// function through its PLT, so this definition in fmpc takes its place (ELF symbol interposition): it throws without
// freeing, and ~tetgenmesh frees once. The signature is tetgen.h's, which this file does not include (it defines the
// function inline); the class is only named.
#include "runtime/meshing/tetgen_mesher.h"

class tetgenmesh;
void terminatetetgen(tetgenmesh* mesh, int code);

__attribute__((visibility("default"))) void terminatetetgen(tetgenmesh*, int code) { throw code; }

namespace fmpc::sim {

// Called by tetgen_mesher.cpp so that the linker takes this file out of the static library (nothing else names it).
bool tetgen_termination_interposed() { return true; }

}  // namespace fmpc::sim
