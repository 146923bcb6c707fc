#pragma once
// Fixture for the layer check: registration must not include compensation (the check must reject this file).
#include "probecomp/compensation/conventional.hpp"
