#include "check.h"
int main(void){return TEST_DONE();}
