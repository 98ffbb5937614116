"""A tiny random-weight SmolVLM, made here with no hub access, for rehearsing SmolVLA's fine-tuning on a CPU.

LeRobot's SmolVLA reads its vision-language backbone from a model directory (`--policy.vlm_model_name`): the
model's config (`AutoConfig`), its processor (`AutoProcessor`: image processor, video processor and tokenizer)
and, with `--policy.load_vlm_weights=false`, no weights. `build_tiny_smolvlm` writes such a directory: a SmolVLM
config with a 2-layer Llama text model and a 1-layer vision encoder at the policy's image size, and a word-level
tokenizer (the `tokenizers` library) whose vocabulary is every sentence and entity name of LangGap's catalogs plus
the special tokens SmolVLM's processor and SmolVLA look up (`fake_image_token`, `image_token`,
`global_image_token`, `end_of_utterance_token`). Every instruction a rehearsal may send is therefore tokenized
without an unknown word.

Needs `transformers` and `tokenizers` (the LeRobot environment).
"""

from __future__ import annotations

from pathlib import Path

from langgap.errors import DependencyNotInstalled

# The special tokens SmolVLM's processor and LeRobot's SmolVLA read from the tokenizer, under SmolVLM2's names.
SPECIAL_TOKENS = {
    "fake_image_token": "<fake_token_around_image>",
    "image_token": "<image>",
    "global_image_token": "<global-img>",
    "end_of_utterance_token": "<end_of_utterance>",
}
PAD, UNK = "<pad>", "<unk>"
PATCH = 16  # vision patch size: a 64 px image is 4 x 4 patches, 4 tokens after SmolVLM's 2 x 2 pixel shuffle
SCALE_FACTOR = 2


def build_tiny_smolvlm(out: str | Path, *, image_size: int, texts: list[str]) -> Path:
    """Write a tiny SmolVLM model directory (config, processor, tokenizer; no weights) to `out`; returns it.

    Args:
        out: The directory to write (created; files in it are replaced).
        image_size: The square image size the policy is trained at (a multiple of 32).
        texts: The sentences whose words make the tokenizer's vocabulary.
    """
    if image_size % (PATCH * SCALE_FACTOR):
        raise ValueError(f"image_size must be a multiple of {PATCH * SCALE_FACTOR}, got {image_size}")
    try:
        from tokenizers import Tokenizer, models, normalizers, pre_tokenizers, trainers
        from transformers import PreTrainedTokenizerFast, SmolVLMConfig, SmolVLMImageProcessor, SmolVLMProcessor
        from transformers.models.smolvlm.video_processing_smolvlm import SmolVLMVideoProcessor
    except ImportError as exc:
        raise DependencyNotInstalled(f"{exc.name} is not installed; run this in .venv-lerobot") from None

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    words = Tokenizer(models.WordLevel(unk_token=UNK))
    words.normalizer = normalizers.Lowercase()
    words.pre_tokenizer = pre_tokenizers.Whitespace()
    words.train_from_iterator(texts, trainers.WordLevelTrainer(special_tokens=[PAD, UNK, *SPECIAL_TOKENS.values()]))
    tokenizer = PreTrainedTokenizerFast(
        tokenizer_object=words, pad_token=PAD, unk_token=UNK, extra_special_tokens=SPECIAL_TOKENS
    )
    config = SmolVLMConfig(
        text_config={
            "model_type": "llama",
            "vocab_size": len(tokenizer),
            "hidden_size": 64,
            "intermediate_size": 128,
            "num_hidden_layers": 2,
            "num_attention_heads": 4,
            "num_key_value_heads": 2,
            "head_dim": 16,
            "max_position_embeddings": 512,
            "pad_token_id": tokenizer.pad_token_id,
        },
        vision_config={
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_hidden_layers": 1,
            "num_attention_heads": 2,
            "image_size": image_size,
            "patch_size": PATCH,
        },
        scale_factor=SCALE_FACTOR,
        image_token_id=tokenizer.convert_tokens_to_ids(SPECIAL_TOKENS["image_token"]),
        vocab_size=len(tokenizer),
    )
    config.save_pretrained(out)
    size = {"longest_edge": image_size}
    processor = SmolVLMProcessor(
        image_processor=SmolVLMImageProcessor(do_image_splitting=False, size=size, max_image_size=size),
        tokenizer=tokenizer,
        video_processor=SmolVLMVideoProcessor(),
        image_seq_len=(image_size // PATCH) ** 2 // SCALE_FACTOR**2,
    )
    processor.save_pretrained(out)
    return out
