// Fixture for the layer check: simulation must not include studies (the check must reject this file).
#include "probecomp/studies/comparison.hpp"
#include "probecomp/geometry/rigid.hpp"
