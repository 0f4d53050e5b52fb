#include "soa/trisoup.h"
