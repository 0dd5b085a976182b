#pragma once
// Loads a real SMPL model that the user converted to .npz (the official files may not be
// redistributed, so we never ship one). Expected arrays, float or int, C or Fortran order:
//   v_template (V, 3)   shapedirs (V, 3, B)   posedirs (V, 3, 207) [optional]
//   J_regressor (24, V) dense   weights (V, 24)   kintree_table (2, 24)   f (F, 3)
// e.g. in Python: np.savez(out, **{k: np.asarray(m[k].todense() if hasattr(m[k], 'todense')
// else m[k]) for k in keys}) from the official pickle.
// Every missing or malformed array raises posefuse::Error naming the key and what is wrong.
#include <map>
#include <memory>
#include <string>

#include "body/npz_reader.hpp"
#include "body/smpl_model.hpp"

namespace posefuse::body {

std::shared_ptr<SmplModel> load_smpl_npz(const std::string& path);
std::shared_ptr<SmplModel> smpl_from_arrays(const std::map<std::string, NpyArray>& arrays);

}  // namespace posefuse::body
