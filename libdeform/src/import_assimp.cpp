// Importer through Assimp (import.hpp): filled in by the importer module.
