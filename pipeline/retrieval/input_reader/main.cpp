// glaswave-read-retrieval-input: reads one of retrieve's inputs whole for read_retrieve_inputs
// (pipeline/retrieval/retrieve_inputs.hpp) in a process of its own, where a crash, a spin or an
// endless allocation inside HDF5 or libnetcdf ends only this program.
#include <unistd.h>

#include "pipeline/retrieval/retrieve_inputs.hpp"

// _exit: what the reader holds goes with the process (as glaswave-read-granule's).
int main(int argc, char** argv) { ::_exit(glaswave::retrieval_input_reader_main(argc, argv)); }
