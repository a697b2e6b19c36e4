#pragma once
// Messages on stderr are text: file names and tokens from user files may hold any bytes, and a
// terminal must not receive raw binary (or control sequences) from an error line. While an
// instance lives, std::cerr passes valid UTF-8, newlines, tabs and carriage returns through and
// shows every other byte as \xHH.

#include <streambuf>
#include <string>

namespace torsion::cli {

class TextOnlyStderr {
 public:
  TextOnlyStderr();
  ~TextOnlyStderr();
  TextOnlyStderr(const TextOnlyStderr&) = delete;
  TextOnlyStderr& operator=(const TextOnlyStderr&) = delete;

 private:
  class Filter : public std::streambuf {
   public:
    explicit Filter(std::streambuf* target) : target_(target) {}
    void flushPending();  ///< an unfinished UTF-8 sequence at the end is shown as \xHH

   protected:
    int_type overflow(int_type c) override;
    int sync() override { return target_->pubsync(); }

   private:
    void put(unsigned char byte);
    void escape(unsigned char byte);
    std::streambuf* target_;
    std::string pending_;  // the bytes of a UTF-8 sequence not yet complete
    size_t needed_ = 0;    // continuation bytes still expected
  };

  std::streambuf* original_;
  Filter filter_;
};

}  // namespace torsion::cli
