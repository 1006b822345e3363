// Load a URDF and extract its DH chain with iDynTree (no verification): the side-by-side of
// urdf-dh's issue 12 section 4.
#include <iDynTree/ModelLoader.h>
#include <iDynTree/DenavitHartenberg.h>
#include <cstdio>
int main(int argc, char** argv) {
    iDynTree::ModelLoader loader;
    if (!loader.loadModelFromFile(argv[1])) return 2;
    iDynTree::DHChain chain;
    if (!iDynTree::ExtractDHChainFromModel(loader.model(), argv[2], argv[3], chain)) return 3;
    for (size_t i = 0; i < chain.getNrOfDOFs(); i++)
        std::printf("%zu a %.6f alpha %.6f d %.6f offset %.6f\n", i, chain(i).A, chain(i).Alpha, chain(i).D, chain(i).Offset);
    return 0;
}
