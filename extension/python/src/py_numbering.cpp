#include "py_numbering.h"

#include <algorithm>

namespace torsion::python {

std::vector<int> bodyNodes(const FemBody& body, std::vector<int> nodes, const std::string& where,
                           bool anchoring) {
  const InputNumbering& numbering = body.inputNumbering();
  const int n = body.model().nodeCount();
  std::vector<char> listed(static_cast<size_t>(n), 0);
  for (int& node : nodes) {
    const std::string named = where + "node " + std::to_string(node);
    if (node < 0 || node >= n)
      throw py::value_error(named + " out of range [0, " + std::to_string(n) + ")");
    if (listed[static_cast<size_t>(node)]++) throw py::value_error(named + " listed twice");
    node = numbering.bodyNode(node);
    if (anchoring && body.contacts().anchors().anchored(node))
      throw py::value_error(named + " is anchored already");
  }
  return nodes;
}

py::array_t<int> inputNodeArray(const FemBody& body, const std::vector<int>& nodes) {
  std::vector<int> input(nodes.size());
  std::transform(nodes.begin(), nodes.end(), input.begin(),
                 [&](int node) { return body.inputNumbering().inputNode(node); });
  std::sort(input.begin(), input.end());
  py::array_t<int> out(static_cast<py::ssize_t>(input.size()));
  std::copy(input.begin(), input.end(), out.mutable_data());
  return out;
}

py::array_t<int> inputElementArray(const FemBody& body) {
  const FemModel& model = body.model();
  const InputNumbering& numbering = body.inputNumbering();
  const int per = model.nodesPerElement();
  const int tets_per_element = model.mesh().tetCount() / model.elementCount();
  py::array_t<int> out(
      {static_cast<py::ssize_t>(model.elementCount()), static_cast<py::ssize_t>(per)});
  int* rows = out.mutable_data();
  for (int c = 0; c < model.elementCount(); ++c) {
    const int e = numbering.bodyElement(c, tets_per_element);
    for (int a = 0; a < per; ++a)
      rows[per * c + a] =
          numbering.inputNode(model.elementNodes()[static_cast<size_t>(per * e + a)]);
  }
  out.attr("setflags")(py::arg("write") = false);
  return out;
}

}  // namespace torsion::python
