#include "python/py_channels.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"
#include "contract/decode.h"

namespace nimble::python {

namespace py = pybind11;

namespace {

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};

/// Appends one message's fields to `c` (its columns made at the first message).
template <class M>
void append(M& m, ChannelColumns& c) {
  const bool first = c.messages == 0;
  std::size_t k = 0;
  for_each_field(m, [&](const char* name, auto& field) {
    using T = std::remove_cv_t<std::remove_reference_t<decltype(field)>>;
    if (first) {
      c.names.emplace_back(name);
      c.columns.emplace_back();
    }
    Column& col = c.columns[k++];
    if constexpr (std::is_arithmetic_v<T>) {
      col.kind = std::is_floating_point_v<T> ? Column::kFloat : Column::kInt;
      if constexpr (std::is_floating_point_v<T>)
        col.f.push_back(field);
      else
        col.i.push_back(static_cast<std::int64_t>(field));
    } else if constexpr (std::is_array_v<T> && std::is_arithmetic_v<std::remove_extent_t<T>>) {
      using E = std::remove_extent_t<T>;
      col.row = true;
      col.width = std::extent_v<T>;
      col.kind = std::is_floating_point_v<E> ? Column::kFloat : Column::kInt;
      for (std::size_t j = 0; j < std::extent_v<T>; ++j) {
        if constexpr (std::is_floating_point_v<E>)
          col.f.push_back(field[j]);
        else
          col.i.push_back(static_cast<std::int64_t>(field[j]));
      }
    } else if constexpr (std::is_same_v<T, std::string>) {
      col.kind = Column::kObject;
      col.strings = true;
      col.scalar_string = true;
      col.so.push_back({field});
    } else if constexpr (is_vector<T>::value) {
      using E = typename T::value_type;
      col.kind = Column::kObject;
      if constexpr (std::is_arithmetic_v<E>) {
        col.fo.emplace_back(field.begin(), field.end());
      } else if constexpr (std::is_same_v<E, std::string>) {
        col.strings = true;
        col.so.push_back(field);
      } else {
        col.fo.emplace_back();  // nested variable-length arrays: not carried
      }
    } else {
      col.kind = Column::kObject;
      col.fo.emplace_back();  // a fixed array of strings or of arrays: not carried
    }
  });
  ++c.messages;
}

template <class M>
void decode_append(const void* data, int size, ChannelColumns& into) {
  M m{};
  if (contract::decode_exact(data, size, m)) append(m, into);
}

}  // namespace

ChannelCollector::ChannelCollector() : worker_([this] { decode_batches(); }) {}

ChannelCollector::~ChannelCollector() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  wake_.notify_one();
  worker_.join();
}

void ChannelCollector::add(const std::string& channel, const void* data, int size) {
  auto [it, fresh] = sinks_.emplace(channel, Sink{});
  if (fresh) {
    if (const contract::ChannelSpec* spec = contract::find_channel(channel)) {
      with_message_type(spec->type, [&](auto type) {
        using M = typename decltype(type)::type;
        // (a new node of channels_: the decoder only ever touches nodes made earlier, through their
        // address, never the tree)
        it->second = Sink{&decode_append<M>, &channels_[channel]};
      });
    }
  }
  const Sink& sink = it->second;
  if (sink.decode == nullptr || size < 0) return;
  const auto* bytes = static_cast<const unsigned char*>(data);
  filling_.items.push_back({sink.decode, sink.columns, filling_.bytes.size(), size});
  filling_.bytes.insert(filling_.bytes.end(), bytes, bytes + size);
  if (filling_.items.size() >= 2048) hand_over();
}

void ChannelCollector::hand_over() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(filling_));
    ++pending_batches_;
  }
  filling_ = Batch{};
  wake_.notify_one();
}

void ChannelCollector::decode_batches() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return done_ || !queue_.empty(); });
    if (queue_.empty()) return;  // done, and nothing left
    std::vector<Batch> batches;
    batches.swap(queue_);
    lock.unlock();
    for (const Batch& b : batches) {
      for (const Batch::Item& item : b.items) item.decode(b.bytes.data() + item.offset, item.size, *item.columns);
    }
    lock.lock();
    pending_batches_ -= batches.size();
    if (pending_batches_ == 0) idle_.notify_all();
  }
}

std::map<std::string, ChannelColumns>& ChannelCollector::channels() {
  if (!filling_.items.empty()) hand_over();
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return pending_batches_ == 0; });
  return channels_;
}

namespace {

/// A numpy array that takes over `values` (no copy): the vector moves to the heap, and the array's
/// base (a capsule) frees it with the array.
template <class T>
py::array_t<T> numpy_of(std::vector<T>&& values, std::size_t n, std::size_t width, bool row) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(n)};
  if (row) shape.push_back(static_cast<py::ssize_t>(width));
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule base(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), base);
}

/// A string field over its messages as one numpy unicode array ('<U' of the longest), filled here:
/// no Python object per message. (The rig's strings are ASCII names; another byte is kept as it is.)
py::array strings_of(const std::vector<std::vector<std::string>>& values) {
  std::size_t width = 1;
  for (const auto& v : values) width = std::max(width, v.front().size());
  py::array a(py::dtype("<U" + std::to_string(width)),
              std::vector<py::ssize_t>{static_cast<py::ssize_t>(values.size())});
  auto* out = static_cast<std::uint32_t*>(a.mutable_data());
  std::fill(out, out + values.size() * width, 0u);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string& text = values[i].front();
    for (std::size_t j = 0; j < text.size(); ++j) out[i * width + j] = static_cast<unsigned char>(text[j]);
  }
  return a;
}

}  // namespace

py::dict channels_dict(ChannelCollector& collector) {
  auto& channels = collector.channels();
  py::dict out;
  py::module_ np = py::module_::import("numpy");
  for (auto& [channel, c] : channels) {
    py::dict fields;
    for (std::size_t k = 0; k < c.names.size(); ++k) {
      Column& col = c.columns[k];
      if (col.kind == Column::kFloat) {
        fields[c.names[k].c_str()] = numpy_of(std::move(col.f), c.messages, col.width, col.row);
      } else if (col.kind == Column::kInt) {
        fields[c.names[k].c_str()] = numpy_of(std::move(col.i), c.messages, col.width, col.row);
      } else {
        if (col.scalar_string) {
          fields[c.names[k].c_str()] = strings_of(col.so);
          continue;
        }
        py::list items;
        if (col.strings) {
          for (const auto& s : col.so) items.append(py::cast(s));
        } else {
          for (auto& v : col.fo) {
            const std::size_t n = v.size();
            items.append(numpy_of(std::move(v), n, 1, false));
          }
        }
        fields[c.names[k].c_str()] = np.attr("array")(items, py::arg("dtype") = "object");
      }
    }
    out[channel.c_str()] = fields;
  }
  return out;
}

}  // namespace nimble::python
