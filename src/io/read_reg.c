#include "soa/regions.h"
