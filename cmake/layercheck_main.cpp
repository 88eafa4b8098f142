// Linked with one layer's whole archive and the layers it declares below it:
// the link fails if any object of the layer refers to a symbol of a layer
// above (cmake/layers.cmake).
int main() { return 0; }
