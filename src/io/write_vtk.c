#include "soa/mesh.h"
